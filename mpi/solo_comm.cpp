#include "mpi/solo_comm.h"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>

#include "base/error.h"

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

std::unique_ptr<TileSource> SoloComm::hand_out(const TileHandout& handout) const {
  return std::make_unique<LocalTiles>(handout.count);
}

}  // namespace rp::dist
