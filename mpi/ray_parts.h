#pragma once
/// Ray and hit files across ranks (raypack trace and diff under mpirun): each rank reads its
/// share of the rays, and the hits of all shares are written into one file in the input order,
/// the bytes one process writes.

#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "io/rayfile.h"
#include "mpi/comm.h"

namespace rp::dist {

/// This rank's share of a batch of n rays, in order: part_records(n) of part {rank, size}
/// (whole packets of 8 rays).
RecordRange share(const Comm& comm, uint64_t n);

/// This rank's share of the rays of `path`, read as read_rays(path, part) does; standard input
/// ("-"), which reaches rank 0 only, is read there and each rank is sent its share(). Collective;
/// a failure on any rank throws on every rank.
std::vector<Ray> read_rays_across(const Comm& comm, const std::string& path);

/// Writes the hits of every rank (`hits`: this rank's share, in rank order) to the hit file
/// `path`, the bytes write_hits() writes for the whole batch: rank 0 opens the output
/// (rp::OutputFile: a temporary beside it) and writes the head, every rank writes its records
/// at their offset through a descriptor of its own (pwrite, fsync: no collective file call, so
/// a rank that cannot open the file fails the run on every rank instead of leaving them
/// waiting), and rank 0 renames the temporary over `path` once every write succeeded. Its folder must be on a file
/// system every rank sees at the same path. A device
/// (/dev/stdout) is written by rank 0, which receives every rank's records. Collective; a
/// failure on any rank throws on every rank, and leaves nothing at `path`.
void write_hits_across(const Comm& comm, const std::string& path, std::span<const HitRecord> hits);

/// The same for any file of records: head(n) declares the n records of every rank (a binary
/// header, or a CSV column line), and each rank's `count` records are the bytes `records`,
/// written after those of the ranks before it (raypack trace --query: occluded, count and
/// all-hits files). Collective; fails as write_hits_across.
void write_records_across(const Comm& comm, const std::string& path, uint64_t count, std::string_view records,
                          const std::function<std::string(uint64_t total)>& head);

}  // namespace rp::dist
