#pragma once
/// Ray and hit files: the batches that cross the backend seam, saved to disk so a trace can
/// be replayed, diffed between backends or produced by another program.
///
/// Two formats each, chosen by the extension (any case): `.csv` is text; `.bin`, `.rays` (ray
/// files) or `.hits` (hit files), or no extension at all (devices such as /dev/stdout), is
/// binary; any other extension is an error naming it. Both formats are described below.
/// Reading follows io/input_file.h (regular files only); the name "-" reads standard
/// input, CSV when it starts with the CSV header line, else binary. Writing follows
/// io/output_file.h (complete or absent; devices such as /dev/null written into, never
/// replaced).
///
/// Binary ray file: a 16-byte header, then `count` 32-byte records.
/// Every field is little-endian; floats are IEEE-754 binary32 stored bit for bit (-0, inf,
/// NaN payloads and denormals survive a round trip unchanged).
/// ```
///   offset  size  field
///        0     4  magic: the ASCII bytes 'R' 'P' 'R' 'Y' (0x52 0x50 0x52 0x59)
///        4     4  version: uint32 = 1
///        8     8  count: uint64, number of rays
///       16  32*n  records, record i at byte 16 + 32*i:
///                   +0 org.x  +4 org.y  +8 org.z   float32
///                  +12 dir.x +16 dir.y +20 dir.z   float32
///                  +24 tnear +28 tfar              float32
/// ```
/// The file is exactly 16 + 32 * count bytes; shorter or longer is an error. Note the record
/// order (org, dir, tnear, tfar) differs from the in-memory Ray (org, tnear, dir, tfar).
///
/// Binary hit file: the same 16-byte header with magic 'R' 'P' 'H' 'T' (0x52 0x50 0x48 0x54),
/// version 2, count = number of hits, then `count` 32-byte records, record i at 16 + 32*i:
/// ```
///   +0 t: float32   +4 prim_id: uint32   +8 u: float32   +12 v: float32
///   +16 ng.x  +20 ng.y  +24 ng.z: float32   +28 instance_id: uint32 (0xffffffff: none)
/// ```
/// The file is exactly 16 + 32 * count bytes. Version 1 files (before instances: 28-byte
/// records, the same fields without instance_id) are still read, every instance_id then
/// kNoInstance; they are no longer written.
///
/// CSV ray file: UTF-8/ASCII text, lines end in "\n" or "\r\n". Line 1 names the columns,
/// comma-separated, in any order: `ox,oy,oz,dx,dy,dz` are needed, `tnear` and `tfar` are
/// optional (0 and inf when absent); it may start with a UTF-8 byte order mark (spreadsheets)
/// and with '#' (numpy.savetxt's `header=`), and names may have blanks around them. Each
/// following line is one ray, one value per column, blanks around a value allowed, no
/// quotes. Numbers are what std::from_chars accepts for float (decimal or exponent notation,
/// optional leading '-', `inf`, `-inf`, `nan`, `-nan`, case-insensitive; no '+', no hex) and
/// must be within the float32 range. Blank lines are accepted only at the end of the file.
/// The writer writes line 1 as `ox,oy,oz,dx,dy,dz,tnear,tfar` and formats every float as
/// printf's `%.9g` in the C locale (std::to_chars, general, precision 9), which reads back
/// to the same bits for every finite value, ±0 and ±inf; every NaN is written `nan`, so a
/// NaN's sign and payload do not survive CSV. The writer ends every line with "\n".
/// A numpy array `a` of shape (n, 8) is written so with
/// `numpy.savetxt("rays.csv", a, delimiter=",", header="ox,oy,oz,dx,dy,dz,tnear,tfar")`.
///
/// CSV hit file: the same rules with the columns `t,prim_id,u,v,ng_x,ng_y,ng_z,instance_id`,
/// all needed but instance_id (-1 when absent: files written before instances still read).
/// prim_id and instance_id are decimal integers in [-1, 4294967294]; -1 stands for kInvalidId
/// (a miss) and kNoInstance (no instance), so a default HitRecord (a miss) is written
/// `inf,-1,0,0,0,0,0,-1`.
///
/// Query files: what `raypack trace --query` writes for the queries beyond the closest hit
/// (core/queries.h), by the extension rule of hit files (check_hit_file_name). Written, not
/// read back by raypack; each binary one has the 16-byte header above with its own magic,
/// version 1:
/// ```
///   occluded  'RPOC'  count = rays, 1-byte records: 1 occluded, 0 not
///   count     'RPCN'  count = rays, 4-byte records: uint32, the hits within [tnear, tfar]
///   all hits  'RPHA'  count = hits, 40-byte records, record i at 16 + 40*i:
///                       +0 ray: uint64, the ray's index in the ray file (from 0)
///                       +8 the 32 bytes of a hit record (version 2 above)
/// ```
/// Their CSV files have the columns `occluded`, `count` and
/// `ray,t,prim_id,u,v,ng_x,ng_y,ng_z,instance_id` (the hit file's after `ray`). An all-hits
/// file lists the hits of ray 0, then ray 1, ..., each ray's sorted by t (then prim_id,
/// instance_id), as Backend::all_hits; a ray without hits has no record.
///
/// Every failure throws rp::Error with a one-line message that starts with the path and
/// names the line (CSV) or the counts and byte sizes (binary), e.g.
/// `rays.bin: the header declares 4000000000 rays (128000000000 bytes) but 64 bytes follow it`
/// or `rays.csv: line 5: 7 values, expected 8`. A declared count is checked against the file
/// size before anything is allocated for it.

#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "base/math.h"
#include "core/ray.h"

namespace rp {

/// One traced hit as stored in hit files: t (+inf on a miss), prim_id (kInvalidId on a miss),
/// barycentrics u, v, the unit geometric normal ng (0,0,0 on a miss) and the instance
/// (kNoInstance for none). 32 bytes in memory and on disk (version 2). t is in units of the
/// ray direction's length (see core/ray.h).
struct HitRecord {
  float t = std::numeric_limits<float>::infinity();  ///< ray parameter of the hit; +inf on a miss
  uint32_t prim_id = kInvalidId;                      ///< primitive index; kInvalidId on a miss
  float u = 0, v = 0;                                 ///< barycentrics as in Hit; 0 on a miss
  Vec3f ng{};                                         ///< unit geometric normal, world space; (0,0,0) on a miss
  uint32_t instance_id = kNoInstance;                 ///< as in Hit
};

/// One hit of an all-hits file: the index of its ray and the hit. 40 bytes.
struct RayHitRecord {
  uint64_t ray = 0;  ///< the ray's index in the ray file, from 0
  HitRecord hit;
};

/// The query files (see the top of this header).
enum class QueryFile { occluded, count, all_hits };

/// One of `count` consecutive shares of a file's rays, for processes that read one file
/// together (raypack trace and diff across MPI ranks); the shares hold every ray once, in file
/// order.
struct FilePart {
  int index = 0;  ///< in [0, count)
  int count = 1;
};

/// Records [first, last) of a batch.
struct RecordRange {
  uint64_t first = 0, last = 0;
};

/// The records of `part` of a batch of `n`: its bounds n * index / count rounded down to a
/// multiple of 8 (so that packets of 8 consecutive rays stay whole); the last part ends at n.
RecordRange part_records(uint64_t n, FilePart part);

/// Throws rp::Error naming `path` when its extension names no ray-file format (see the top of
/// this header), so a command can refuse the name before any work.
void check_ray_file_name(const std::string& path);

/// The same for hit files.
void check_hit_file_name(const std::string& path);

/// Reads rays from `path` in the format its extension names (standard input "-": CSV when
/// line 1 is a ray-file header, else binary). Reads only; any malformed byte or line throws rp::Error naming the path and the
/// line or byte count (see the top of this header for the formats and messages).
std::vector<Ray> read_rays(const std::string& path);

/// Reads `part` of the rays of `path`, a file (not standard input). Binary: the records of
/// part_records(); CSV: the lines that start in the part's share of the bytes after line 1
/// (from the body's size times index / count up to the next part's). Every part checks what
/// read_rays checks, and names a line by its number in the whole file: the lines before a
/// part's own are read, not parsed, so the count and the blank-line rule see the whole file.
/// So when read_rays refuses a file, the lowest part that throws gives read_rays' message.
std::vector<Ray> read_rays(const std::string& path, FilePart part);

/// Writes `rays` to `path` in the format its extension names, by rp::OutputFile: `path` is never half-written; on failure rp::Error
/// `<path>: cannot write: <reason>` is thrown and no temporary file is left.
void write_rays(const std::string& path, std::span<const Ray> rays);

/// Reads hits from `path` in the format its extension names. Reads only; errors as read_rays (a ray file is rejected by its magic 'RPRY').
std::vector<HitRecord> read_hits(const std::string& path);

/// Writes `hits` to `path` in the format the extension selects (binary version 2), by
/// rp::OutputFile exactly as write_rays; prim_id kInvalidId and instance_id kNoInstance are
/// written -1 in CSV. The file's bytes are hit_file_head(path, hits.size()) followed by
/// append_hit_records(path, hits).
void write_hits(const std::string& path, std::span<const HitRecord> hits);

/// The bytes of a hit file at `path` (its format by the extension, as write_hits) before its
/// records: the 16-byte header declaring `count` hits, or the CSV column line.
std::string hit_file_head(const std::string& path, uint64_t count);

/// Appends `hits` to `out` as consecutive records of a hit file at `path`: 32 bytes each, or
/// one line each. Records of consecutive batches follow each other, so processes can write
/// their batches' records at offsets that add up (raypack trace across MPI ranks).
void append_hit_records(const std::string& path, std::span<const HitRecord> hits, std::string& out);

/// The bytes of a query file of `kind` at `path` (its format by the extension, as hit files)
/// before its records: the 16-byte header declaring `count` records, or the CSV column line.
std::string query_file_head(QueryFile kind, const std::string& path, uint64_t count);

/// Appends records of an occluded file at `path` to `out`: one per ray, 1 when occluded[i] is
/// not 0. Records of consecutive batches follow each other, as append_hit_records'.
void append_occluded_records(const std::string& path, std::span<const uint8_t> occluded, std::string& out);

/// Appends records of a count file: one per ray.
void append_count_records(const std::string& path, std::span<const uint32_t> counts, std::string& out);

/// Appends records of an all-hits file: one per hit.
void append_all_hits_records(const std::string& path, std::span<const RayHitRecord> hits, std::string& out);

}  // namespace rp
