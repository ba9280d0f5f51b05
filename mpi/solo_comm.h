#pragma once
/// The Comm of a run in one process: every collective is the identity, agree() rethrows this
/// process's own failure, and the tiles of a render are taken in turn by its threads.

#include "mpi/comm.h"

namespace rp::dist {

class SoloComm : public Comm {
 public:
  int rank() const override { return 0; }
  int size() const override { return 1; }
  void agree(std::exception_ptr mine) const override;
  void broadcast(std::string&) const override {}
  void sum(std::span<uint64_t>) const override {}
  uint64_t sum_before(uint64_t) const override { return 0; }
  std::string gather(std::string_view bytes, bool) const override { return std::string(bytes); }
  std::string scatter(std::span<const std::string> parts) const override;
  std::unique_ptr<TileSource> hand_out(const TileHandout& handout) const override;
};

}  // namespace rp::dist
