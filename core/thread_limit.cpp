#include "core/thread_limit.h"

#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <algorithm>

#include "base/error.h"

namespace rp {

struct ThreadLimit::Control {
  explicit Control(size_t threads) : limit(tbb::global_control::max_allowed_parallelism, threads) {}
  tbb::global_control limit;
};

ThreadLimit::ThreadLimit(int threads) {
  RP_CHECK(threads >= 0, "thread limit: ", threads, " is negative (0 sets no limit: every core)");
  if (threads > 0) control_ = std::make_unique<Control>(size_t(threads));
}

ThreadLimit::~ThreadLimit() = default;

int max_threads() noexcept {
  const size_t limit = tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism);
  return int(std::max<size_t>(1, std::min(size_t(tbb::this_task_arena::max_concurrency()), limit)));
}

}  // namespace rp
