#include "io/rayfile.h"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string_view>

#include "base/error.h"
#include "base/text.h"
#include "io/csv.h"
#include "io/input_file.h"
#include "io/output_file.h"

namespace rp {

namespace {

// The binary formats are little-endian IEEE-754; this build stores floats as they are in memory.
static_assert(std::endian::native == std::endian::little, "rayfile.cpp assumes a little-endian machine");
static_assert(std::numeric_limits<float>::is_iec559 && sizeof(float) == 4, "float must be IEEE-754 binary32");
static_assert(sizeof(HitRecord) == 32, "HitRecord is 32 bytes");

constexpr size_t kHeaderBytes = 16;
constexpr size_t kChunkRecords = 4096;  // records decoded or encoded per read / write call

/// What tells the binary formats apart: the magic, and the version (with its record size).
struct BinaryFormat {
  const char* magic;      // 4 ASCII bytes
  const char* kind;       // "ray" / "hit" in "not a raypack ray file"
  const char* one;        // noun for a count of 1
  const char* many;       // noun for other counts
  uint32_t version;       // the version this writer writes
  size_t record_bytes;    // of that version
  uint32_t old_version;   // an older version still read (0: none)
  size_t old_record_bytes;
};
constexpr BinaryFormat kRayFormat{"RPRY", "ray", "ray", "rays", 1, 32, 0, 0};
/// Version 2 added instance_id to each record; version 1's 28-byte records are still read.
constexpr BinaryFormat kHitFormat{"RPHT", "hit", "hit", "hits", 2, 32, 1, 28};

/// The files of the other queries of raypack trace; written, never read back here.
constexpr BinaryFormat kOccludedFormat{"RPOC", "occluded", "ray", "rays", 1, 1, 0, 0};
constexpr BinaryFormat kCountFormat{"RPCN", "count", "ray", "rays", 1, 4, 0, 0};
constexpr BinaryFormat kAllHitsFormat{"RPHA", "all-hits", "hit", "hits", 1, 40, 0, 0};
static_assert(sizeof(RayHitRecord) == 40, "RayHitRecord is 40 bytes");

constexpr csv::Columns kRayColumns{{"ox", "oy", "oz", "dx", "dy", "dz", "tnear", "tfar"},
                                   8,
                                   6,
                                   {nullptr, nullptr, nullptr, nullptr, nullptr, nullptr, "0", "inf"}};
constexpr csv::Columns kHitColumns{{"t", "prim_id", "u", "v", "ng_x", "ng_y", "ng_z", "instance_id"},
                                   8,
                                   7,
                                   {nullptr, nullptr, nullptr, nullptr, nullptr, nullptr, nullptr, "-1"}};
constexpr csv::Columns kOccludedColumns{{"occluded"}, 1, 1, {}};
constexpr csv::Columns kCountColumns{{"count"}, 1, 1, {}};
constexpr csv::Columns kAllHitsColumns{
    {"ray", "t", "prim_id", "u", "v", "ng_x", "ng_y", "ng_z", "instance_id"}, 9, 9, {}};

/// The format `path` names for a file of `fmt`'s kind: .csv (any case) CSV; .bin, .rays /
/// .hits or no extension (devices such as /dev/stdout) binary; any other extension an error.
bool is_csv(const std::string& path, const BinaryFormat& fmt) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".csv") return true;
  if (ext.empty() || ext == ".bin" || ext == std::string(".") + fmt.many) return false;
  throw Error(cat(path, ": unknown ", fmt.kind, " file extension '", printable(ext), "' (.csv for text; .bin, .", fmt.many,
                  " or none for binary)"));
}

/// count * k in decimal, exact even when the product does not fit in 64 bits.
std::string times(uint64_t count, uint64_t k) {
  if (k == 0 || count <= UINT64_MAX / k) return std::to_string(count * k);
  std::string digits = std::to_string(count);
  uint64_t carry = 0;
  for (auto it = digits.rbegin(); it != digits.rend(); ++it) {
    const uint64_t x = uint64_t(*it - '0') * k + carry;
    *it = char('0' + x % 10);
    carry = x / 10;
  }
  for (; carry != 0; carry /= 10) digits.insert(digits.begin(), char('0' + carry % 10));
  return digits;
}

/// True when `in` is CSV: by the extension of its path, or for standard input ("-") by its
/// first line being a header of `columns`.
bool is_csv(const InputFile& in, const BinaryFormat& fmt, const csv::Columns& columns) {
  if (in.path() != "-") return is_csv(in.path(), fmt);
  const std::string_view text = in.memory();
  std::string why;
  return !csv::parse_header(text.substr(0, text.find('\n')), columns, why).empty();
}

/// The bytes of a binary file, read in order; their total is known up front.
class ByteSource {
 public:
  explicit ByteSource(InputFile& in) : in_(in) {}

  uint64_t size() const { return in_.size(); }

  /// Reads the next n bytes; callers never ask past size().
  void read(unsigned char* dst, size_t n) {
    if (std::fread(dst, 1, n, in_.get()) != n) in_.fail_read(offset_);
    offset_ += n;
  }
  /// Moves past the next n bytes without reading them.
  void skip(uint64_t n) {
    if (n > 0 && ::fseeko(in_.get(), off_t(offset_ + n), SEEK_SET) != 0) in_.fail_read(offset_);
    offset_ += n;
  }

 private:
  InputFile& in_;
  uint64_t offset_ = 0;
};

uint32_t load_u32(const unsigned char* p) {
  uint32_t v;
  std::memcpy(&v, p, 4);
  return v;
}
uint64_t load_u64(const unsigned char* p) {
  uint64_t v;
  std::memcpy(&v, p, 8);
  return v;
}

/// Reads the records of `part` of a binary file of `fmt` (its version or the old one it still
/// reads), decoding each record with decode(bytes, version, Record&).
template <typename Record, typename Decode>
std::vector<Record> read_binary(InputFile& in, const BinaryFormat& fmt, Decode decode, FilePart part) {
  const std::string& path = in.path();
  ByteSource src(in);
  const uint64_t size = src.size();
  unsigned char header[kHeaderBytes] = {};
  src.read(header, size_t(std::min<uint64_t>(size, kHeaderBytes)));
  if (size >= 4 && std::memcmp(header, fmt.magic, 4) != 0)
    throw Error(cat(path, ": not a raypack ", fmt.kind, " file (magic '",
                    printable({reinterpret_cast<const char*>(header), 4}), "', expected '", fmt.magic, "')"));
  if (size < kHeaderBytes)
    throw Error(cat(path, ": truncated: ", size, " bytes, the header needs ", kHeaderBytes));
  const uint32_t version = load_u32(header + 4);
  if (version != fmt.version && (fmt.old_version == 0 || version != fmt.old_version))
    throw Error(cat(path, ": unsupported version ", version, " (",
                    fmt.old_version ? cat(fmt.old_version, " or ", fmt.version) : cat(fmt.version), ")"));
  const size_t record_bytes = version == fmt.version ? fmt.record_bytes : fmt.old_record_bytes;
  const uint64_t count = load_u64(header + 8);
  const uint64_t follow = size - kHeaderBytes;
  // Checked before anything is allocated: a corrupt count must not reserve memory.
  if (count > follow / record_bytes || count * record_bytes != follow)
    throw Error(cat(path, ": the header declares ", count, " ", count == 1 ? fmt.one : fmt.many, " (",
                    times(count, record_bytes), " bytes) but ", follow, " bytes follow it"));

  const RecordRange range = part_records(count, part);
  src.skip(range.first * record_bytes);
  std::vector<Record> out(static_cast<size_t>(range.last - range.first));
  std::vector<unsigned char> chunk(kChunkRecords * record_bytes);
  for (size_t first = 0; first < out.size(); first += kChunkRecords) {
    const size_t n = std::min(kChunkRecords, out.size() - first);
    src.read(chunk.data(), n * record_bytes);
    for (size_t i = 0; i < n; ++i) decode(chunk.data() + i * record_bytes, version, out[first + i]);
  }
  return out;
}

// Records are copied field by field with memcpy so every bit pattern (signalling NaNs
// included) is kept.
void decode_ray(const unsigned char* p, uint32_t, Ray& r) {
  std::memcpy(&r.org.x, p + 0, 4);
  std::memcpy(&r.org.y, p + 4, 4);
  std::memcpy(&r.org.z, p + 8, 4);
  std::memcpy(&r.dir.x, p + 12, 4);
  std::memcpy(&r.dir.y, p + 16, 4);
  std::memcpy(&r.dir.z, p + 20, 4);
  std::memcpy(&r.tnear, p + 24, 4);
  std::memcpy(&r.tfar, p + 28, 4);
}
void encode_ray(const Ray& r, unsigned char* p) {
  std::memcpy(p + 0, &r.org.x, 4);
  std::memcpy(p + 4, &r.org.y, 4);
  std::memcpy(p + 8, &r.org.z, 4);
  std::memcpy(p + 12, &r.dir.x, 4);
  std::memcpy(p + 16, &r.dir.y, 4);
  std::memcpy(p + 20, &r.dir.z, 4);
  std::memcpy(p + 24, &r.tnear, 4);
  std::memcpy(p + 28, &r.tfar, 4);
}
void decode_hit(const unsigned char* p, uint32_t version, HitRecord& h) {
  std::memcpy(&h.t, p + 0, 4);
  std::memcpy(&h.prim_id, p + 4, 4);
  std::memcpy(&h.u, p + 8, 4);
  std::memcpy(&h.v, p + 12, 4);
  std::memcpy(&h.ng.x, p + 16, 4);
  std::memcpy(&h.ng.y, p + 20, 4);
  std::memcpy(&h.ng.z, p + 24, 4);
  h.instance_id = kNoInstance;
  if (version >= 2) std::memcpy(&h.instance_id, p + 28, 4);
}
void encode_hit(const HitRecord& h, unsigned char* p) {
  std::memcpy(p + 0, &h.t, 4);
  std::memcpy(p + 4, &h.prim_id, 4);
  std::memcpy(p + 8, &h.u, 4);
  std::memcpy(p + 12, &h.v, 4);
  std::memcpy(p + 16, &h.ng.x, 4);
  std::memcpy(p + 20, &h.ng.y, 4);
  std::memcpy(p + 24, &h.ng.z, 4);
  std::memcpy(p + 28, &h.instance_id, 4);
}
void encode_occluded(uint8_t occluded, unsigned char* p) { *p = occluded ? 1 : 0; }
void encode_count(uint32_t count, unsigned char* p) { std::memcpy(p, &count, 4); }
void encode_ray_hit(const RayHitRecord& h, unsigned char* p) {
  std::memcpy(p, &h.ray, 8);
  encode_hit(h.hit, p + 8);
}

/// The 16-byte header of a binary file of `fmt` with `count` records.
std::string binary_head(const BinaryFormat& fmt, uint64_t count) {
  unsigned char header[kHeaderBytes];
  std::memcpy(header, fmt.magic, 4);
  std::memcpy(header + 4, &fmt.version, 4);
  std::memcpy(header + 8, &count, 8);
  return {reinterpret_cast<const char*>(header), kHeaderBytes};
}

/// Appends `records` to `out` as binary records of `fmt`, each encoded by encode(record, bytes).
template <typename Record, typename Encode>
void append_binary(std::span<const Record> records, const BinaryFormat& fmt, Encode encode, std::string& out) {
  const size_t at = out.size();
  out.resize(at + records.size() * fmt.record_bytes);
  for (size_t i = 0; i < records.size(); ++i)
    encode(records[i], reinterpret_cast<unsigned char*>(out.data() + at + i * fmt.record_bytes));
}

/// Writes `head`, then the records, kChunkRecords at a time, each chunk's bytes made by
/// append(chunk, bytes).
template <typename Record, typename Append>
void write_records(const std::string& path, const std::string& head, std::span<const Record> records, Append append) {
  OutputFile out(path);
  out.write(head.data(), head.size());
  std::string bytes;
  for (size_t first = 0; first < records.size(); first += kChunkRecords) {
    bytes.clear();
    append(records.subspan(first, std::min(kChunkRecords, records.size() - first)), bytes);
    out.write(bytes.data(), bytes.size());
  }
  out.commit();
}

/// A prim_id or instance_id (`what`): a decimal integer in [-1, 0xfffffffe], -1 for
/// 0xffffffff (kInvalidId, kNoInstance).
uint32_t parse_id(const csv::Place& at, std::string_view s, const char* what) {
  int64_t v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || end != s.data() + s.size() || ec != std::errc() || v < -1 || v >= int64_t(kInvalidId))
    throw Error(cat(at.path, ": line ", at.line, ": '", printable(s), "' is not ", what));
  return v == -1 ? kInvalidId : uint32_t(v);
}

/// The records of `part` of a CSV file of `columns` (csv::read_rows), each line made into one
/// by make(place, values).
template <typename Record, typename Make>
std::vector<Record> read_csv(InputFile& in, const csv::Columns& columns, Make make, FilePart part) {
  std::vector<Record> out;
  csv::read_rows(in, columns, part.index, part.count,
                 [&](const csv::Place& at, const std::string_view* values) { out.push_back(make(at, values)); });
  return out;
}

/// Appends `records` to `out` as CSV lines, each formed by line(record, text).
template <typename Record, typename Line>
void append_csv(std::span<const Record> records, Line line, std::string& out) {
  for (const Record& r : records) {
    line(r, out);
    out += '\n';
  }
}

void ray_line(const Ray& r, std::string& s) {
  const float v[8] = {r.org.x, r.org.y, r.org.z, r.dir.x, r.dir.y, r.dir.z, r.tnear, r.tfar};
  for (int i = 0; i < 8; ++i) {
    if (i) s += ',';
    csv::append_float(s, v[i]);
  }
}

void hit_line(const HitRecord& h, std::string& s) {
  const auto id = [](uint32_t v) { return v == kInvalidId ? std::string("-1") : std::to_string(v); };
  csv::append_float(s, h.t);
  s += ',' + id(h.prim_id);
  for (float x : {h.u, h.v, h.ng.x, h.ng.y, h.ng.z}) {
    s += ',';
    csv::append_float(s, x);
  }
  s += ',' + id(h.instance_id);
}

void occluded_line(uint8_t occluded, std::string& s) { s += occluded ? '1' : '0'; }
void count_line(uint32_t count, std::string& s) { s += std::to_string(count); }
void ray_hit_line(const RayHitRecord& h, std::string& s) {
  s += std::to_string(h.ray) + ',';
  hit_line(h.hit, s);
}

}  // namespace

void check_ray_file_name(const std::string& path) {
  if (path != "-") is_csv(path, kRayFormat);
}

void check_hit_file_name(const std::string& path) {
  if (path != "-") is_csv(path, kHitFormat);
}

RecordRange part_records(uint64_t n, FilePart part) {
  RP_CHECK(part.count >= 1 && part.index >= 0 && part.index < part.count, "file part ", part.index, " of ", part.count);
  const auto bound = [&](int i) { return i == part.count ? n : csv::share_of(n, i, part.count) / 8 * 8; };
  return {bound(part.index), bound(part.index + 1)};
}

std::vector<Ray> read_rays(const std::string& path) { return read_rays(path, FilePart{}); }

std::vector<Ray> read_rays(const std::string& path, FilePart part) {
  RP_CHECK(path != "-" || part.count == 1, "standard input cannot be read in parts");
  InputFile in(path);
  if (!is_csv(in, kRayFormat, kRayColumns)) return read_binary<Ray>(in, kRayFormat, decode_ray, part);
  return read_csv<Ray>(
      in, kRayColumns,
      [](const csv::Place& at, const std::string_view* s) {
        Ray r;
        r.org = {csv::parse_float(at, s[0]), csv::parse_float(at, s[1]), csv::parse_float(at, s[2])};
        r.dir = {csv::parse_float(at, s[3]), csv::parse_float(at, s[4]), csv::parse_float(at, s[5])};
        r.tnear = csv::parse_float(at, s[6]);
        r.tfar = csv::parse_float(at, s[7]);
        return r;
      },
      part);
}

void write_rays(const std::string& path, std::span<const Ray> rays) {
  if (!is_csv(path, kRayFormat))
    return write_records(path, binary_head(kRayFormat, rays.size()), rays, [](std::span<const Ray> chunk, std::string& out) {
      append_binary(chunk, kRayFormat, encode_ray, out);
    });
  write_records(path, csv::head(kRayColumns), rays,
                [](std::span<const Ray> chunk, std::string& out) { append_csv(chunk, ray_line, out); });
}

std::vector<HitRecord> read_hits(const std::string& path) {
  InputFile in(path);
  if (!is_csv(in, kHitFormat, kHitColumns)) return read_binary<HitRecord>(in, kHitFormat, decode_hit, FilePart{});
  return read_csv<HitRecord>(
      in, kHitColumns,
      [](const csv::Place& at, const std::string_view* s) {
        HitRecord h;
        h.t = csv::parse_float(at, s[0]);
        h.prim_id = parse_id(at, s[1], "a primitive id");
        h.u = csv::parse_float(at, s[2]);
        h.v = csv::parse_float(at, s[3]);
        h.ng = {csv::parse_float(at, s[4]), csv::parse_float(at, s[5]), csv::parse_float(at, s[6])};
        h.instance_id = parse_id(at, s[7], "an instance id");
        return h;
      },
      FilePart{});
}

std::string hit_file_head(const std::string& path, uint64_t count) {
  return is_csv(path, kHitFormat) ? csv::head(kHitColumns) : binary_head(kHitFormat, count);
}

void append_hit_records(const std::string& path, std::span<const HitRecord> hits, std::string& out) {
  if (is_csv(path, kHitFormat)) return append_csv(hits, hit_line, out);
  append_binary(hits, kHitFormat, encode_hit, out);
}

void write_hits(const std::string& path, std::span<const HitRecord> hits) {
  write_records(path, hit_file_head(path, hits.size()), hits,
                [&](std::span<const HitRecord> chunk, std::string& out) { append_hit_records(path, chunk, out); });
}

std::string query_file_head(QueryFile kind, const std::string& path, uint64_t count) {
  static constexpr const BinaryFormat* kFormats[] = {&kOccludedFormat, &kCountFormat, &kAllHitsFormat};
  static constexpr const csv::Columns* kColumns[] = {&kOccludedColumns, &kCountColumns, &kAllHitsColumns};
  const auto k = size_t(kind);
  return is_csv(path, kHitFormat) ? csv::head(*kColumns[k]) : binary_head(*kFormats[k], count);
}

void append_occluded_records(const std::string& path, std::span<const uint8_t> occluded, std::string& out) {
  if (is_csv(path, kHitFormat)) return append_csv(occluded, occluded_line, out);
  append_binary(occluded, kOccludedFormat, encode_occluded, out);
}

void append_count_records(const std::string& path, std::span<const uint32_t> counts, std::string& out) {
  if (is_csv(path, kHitFormat)) return append_csv(counts, count_line, out);
  append_binary(counts, kCountFormat, encode_count, out);
}

void append_all_hits_records(const std::string& path, std::span<const RayHitRecord> hits, std::string& out) {
  if (is_csv(path, kHitFormat)) return append_csv(hits, ray_hit_line, out);
  append_binary(hits, kAllHitsFormat, encode_ray_hit, out);
}

}  // namespace rp
