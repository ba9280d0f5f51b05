#include "mpi/ray_parts.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <optional>

#include "base/error.h"
#include "io/output_file.h"

namespace rp::dist {

namespace {

/// Writes `bytes` at byte `offset` of the existing file `path`, every write checked and the
/// data on disk (fsync) before it returns; rp::Error naming the path otherwise. Each rank
/// writes its share of a hit file through a descriptor of its own: nothing collective can
/// fail on one rank and leave the others waiting.
void write_at(const std::string& path, uint64_t offset, std::string_view bytes) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
  if (fd < 0) throw Error(cat(path, ": cannot write: ", std::strerror(errno)));
  const auto fail = [&](int e) {
    ::close(fd);
    throw Error(cat(path, ": cannot write: ", std::strerror(e)));
  };
  if (const int e = pwrite_all(fd, bytes.data(), bytes.size(), offset)) fail(e);
  if (::fsync(fd) != 0) fail(errno);
  if (::close(fd) != 0) throw Error(cat(path, ": cannot write: ", std::strerror(errno)));
}

}  // namespace

RecordRange share(const Comm& comm, uint64_t n) { return part_records(n, {comm.rank(), comm.size()}); }

std::vector<Ray> read_rays_across(const Comm& comm, const std::string& path) {
  if (path != "-") return together(comm, [&] { return read_rays(path, {comm.rank(), comm.size()}); });
  std::vector<std::string> parts;
  together(comm, [&] {
    if (!comm.root()) return;
    const std::vector<Ray> rays = read_rays(path);
    for (int r = 0; r < comm.size(); ++r) {
      const RecordRange range = part_records(rays.size(), {r, comm.size()});
      parts.emplace_back(reinterpret_cast<const char*>(rays.data() + range.first), (range.last - range.first) * sizeof(Ray));
    }
  });
  const std::string mine = comm.scatter(parts);
  parts.clear();
  std::vector<Ray> rays(mine.size() / sizeof(Ray));
  if (!rays.empty()) std::memcpy(rays.data(), mine.data(), mine.size());
  return rays;
}

void write_hits_across(const Comm& comm, const std::string& path, std::span<const HitRecord> hits) {
  const std::string records = together(comm, [&] {
    std::string bytes;
    append_hit_records(path, hits, bytes);
    return bytes;
  });
  write_records_across(comm, path, hits.size(), records, [&](uint64_t n) { return hit_file_head(path, n); });
}

void write_records_across(const Comm& comm, const std::string& path, uint64_t count, std::string_view records,
                          const std::function<std::string(uint64_t total)>& head_of) {
  uint64_t total[] = {count};
  comm.sum(total);
  const std::string head = together(comm, [&] { return head_of(total[0]); });
  // Rank 0 opens the output and writes the head; the others learn where their records go:
  // the temporary file's absolute path, or nothing for a device.
  std::optional<OutputFile> out;
  std::string temp;
  together(comm, [&] {
    if (!comm.root()) return;
    out.emplace(path);
    out->write(head.data(), head.size());
    if (!out->into_device()) temp = std::filesystem::absolute(out->temp_path()).string();
  });
  comm.broadcast(temp);
  if (temp.empty()) {
    const std::string all = comm.gather(records);
    together(comm, [&] {
      if (!comm.root()) return;
      out->write(all.data(), all.size());
      out->commit();
    });
    return;
  }
  const uint64_t offset = head.size() + comm.sum_before(records.size());
  together(comm, [&] { write_at(temp, offset, records); });
  together(comm, [&] {
    if (comm.root()) out->commit();
  });
}

}  // namespace rp::dist
