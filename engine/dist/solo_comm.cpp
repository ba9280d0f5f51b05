#include "engine/dist/solo_comm.h"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>

#include "engine/error.h"

namespace rp::dist {

namespace {

/// Every tile to this process's threads, in order.
class LocalTiles : public TileSource {
 public:
  explicit LocalTiles(int count) : count_(count) {}
  int next() override {
    if (cancelled_.load()) return -1;
    const int t = next_.fetch_add(1);
    return t < count_ ? t : -1;
  }
  void done() override { ++done_; }
  double progress() const override { return count_ ? double(done_.load()) / double(count_) : 1.0; }
  void cancel() override { cancelled_ = true; }
  HandoutStats finish() override { return {}; }

 private:
  int count_;
  std::atomic<int> next_{0}, done_{0};
  std::atomic<bool> cancelled_{false};
};

}  // namespace

void SoloComm::agree(std::exception_ptr mine) const {
  if (mine) std::rethrow_exception(mine);
}

std::string SoloComm::scatter(std::span<const std::string> parts) const {
  RP_CHECK(parts.size() == 1, "scatter: ", parts.size(), " parts for one process");
  return parts[0];
}

void SoloComm::write_at(const std::string& path, uint64_t offset, std::string_view bytes) const {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
  if (fd < 0) throw Error(cat(path, ": cannot write: ", std::strerror(errno)));
  while (!bytes.empty()) {
    const ssize_t n = ::pwrite(fd, bytes.data(), bytes.size(), off_t(offset));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int e = errno;
      ::close(fd);
      throw Error(cat(path, ": cannot write: ", std::strerror(e)));
    }
    bytes.remove_prefix(size_t(n));
    offset += uint64_t(n);
  }
  if (::close(fd) != 0) throw Error(cat(path, ": cannot write: ", std::strerror(errno)));
}

std::unique_ptr<TileSource> SoloComm::hand_out(const TileHandout& handout) const {
  return std::make_unique<LocalTiles>(handout.count);
}

}  // namespace rp::dist
