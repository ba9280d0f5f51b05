#pragma once
/// How many threads raypack's parallel calls use: a limit held for a scope (rp::ThreadLimit)
/// and the number in effect (rp::max_threads()).
///
/// The parallel calls run on TBB's threads inside libraypack.so: intersect_parallel,
/// occluded_parallel and for_each_chunk (core/backend.h), inside and signed_distance
/// (core/queries.h), render and render_aovs (render/render.h), Reference's constructor and its
/// intersect over spans (analysis/reference.h), and the builds and updates of both backends
/// (make_backend, Backend::update; Embree's through the same TBB). TBB is not part of the API (no public
/// header includes it); a program limits those threads here. Without a limit they use every
/// core. A limit changes how fast the calls run, not what they return: tracing, rendering and
/// the simd backend's builds give the same bits for any thread count (docs/conventions.md).

#include <memory>

namespace rp {

/// Limits every raypack parallel call, started from any thread of the process, to at most
/// `threads` threads (the calling thread included) for as long as the object lives, as
/// tbb::global_control(max_allowed_parallelism) does; 1 runs each call on its caller's thread
/// alone. 0 sets no limit: every core (the -t 0 of the raypack command, threads=0 in Python).
/// More threads than cores limit nothing beyond the cores.
///
/// Limits nest and overlap, on one thread or several: the smallest alive is in effect, and
/// when it ends the next smallest applies again, whatever the order they end in. A limit is
/// process-wide (a library that sets one for a call of its own limits the whole program
/// meanwhile); set it before the calls it is meant for.
///
/// Throws rp::Error for a negative `threads`.
class ThreadLimit {
 public:
  explicit ThreadLimit(int threads);
  ~ThreadLimit();
  ThreadLimit(const ThreadLimit&) = delete;
  ThreadLimit& operator=(const ThreadLimit&) = delete;

 private:
  struct Control;
  std::unique_ptr<Control> control_;  ///< null for 0: no limit
};

/// The most threads a parallel call started from the calling thread may use now: the smallest
/// ThreadLimit alive, or the cores TBB may use (its default, which follows the process's CPU
/// affinity) when none is; within a TBB task arena, at most that arena's concurrency. At
/// least 1.
int max_threads() noexcept;

}  // namespace rp
