// rp::ThreadLimit and rp::max_threads (core/thread_limit.h): the limit in effect is the
// smallest alive, whatever the order limits end in; 0 sets none; a negative count is an
// error; under a limit of n a parallel call runs on at most n threads, under 1 on its caller's.

#include "core/thread_limit.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <mutex>
#include <optional>
#include <set>
#include <thread>

#include "core/backend.h"
#include "tests/support/error_of.h"

namespace rp {
namespace {

/// The threads for_each_chunk runs the chunks of `n` rays on.
std::set<std::thread::id> chunk_threads(size_t n) {
  std::mutex mutex;
  std::set<std::thread::id> ids;
  for_each_chunk(n, [&](size_t, size_t) {
    // Long enough per chunk that idle workers, where allowed, take some chunks.
    std::this_thread::sleep_for(std::chrono::microseconds(200));
    const std::lock_guard lock(mutex);
    ids.insert(std::this_thread::get_id());
  });
  return ids;
}

TEST(ThreadLimit, TheSmallestLimitAliveIsInEffect) {
  const int cores = max_threads();
  ASSERT_GE(cores, 1);
  std::optional<ThreadLimit> three(3), one, none;
  EXPECT_EQ(max_threads(), std::min(cores, 3));
  one.emplace(1);
  EXPECT_EQ(max_threads(), 1);
  none.emplace(0);  // sets no limit: the 1 still holds
  EXPECT_EQ(max_threads(), 1);
  three.reset();  // ends before the smaller one it enclosed
  EXPECT_EQ(max_threads(), 1);
  one.reset();
  EXPECT_EQ(max_threads(), cores);
}

TEST(ThreadLimit, ANegativeCountIsAnError) {
  EXPECT_EQ(test::error_of([] { const ThreadLimit limit(-1); }),
            "thread limit: -1 is negative (0 sets no limit: every core)");
  EXPECT_EQ(test::error_of([] { const ThreadLimit limit(0); }), test::kNoError);
}

TEST(ThreadLimit, OneRunsEveryChunkOnTheCallersThread) {
  const size_t n = 64 * kParallelChunk;
  {
    const ThreadLimit limit(1);
    EXPECT_EQ(chunk_threads(n), std::set<std::thread::id>{std::this_thread::get_id()});
  }
  const ThreadLimit limit(2);
  EXPECT_LE(chunk_threads(n).size(), 2u);
}

}  // namespace
}  // namespace rp
