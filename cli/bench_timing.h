#pragma once
// What `raypack bench` times: rays of one kind, and how a timing is repeated until it is steady.

#include <algorithm>
#include <chrono>
#include <string>
#include <utility>
#include <vector>

#include "analysis/reference.h"
#include "cli/bench_cmd.h"
#include "core/ray.h"

namespace rp::cli {

/// The median of `v` (sorted in place, not empty) and its spread, (max - min) / median.
inline std::pair<double, double> median_spread(std::vector<double>& v) {
  std::sort(v.begin(), v.end());
  const double med = v[v.size() / 2];
  return {med, med > 0 ? (v.back() - v.front()) / med : 0.0};
}

/// Timing runs until the spread of the last min_runs is below the target (or max_runs).
struct Timing {
  double median_mrays = 0, spread = 0;  ///< spread: (max - min) / median over the runs kept
  int runs = 0;
};

/// Runs trace() once untimed, then until the spread of the last min_runs runs is below
/// the target (or max_runs); the rays per second of their median.
template <typename Trace>
Timing time_it(size_t rays, const BenchArgs& a, Trace&& trace) {
  trace();  // warm-up, untimed
  std::vector<double> secs;
  Timing t;
  while (int(secs.size()) < a.max_runs) {
    const auto start = std::chrono::steady_clock::now();
    trace();
    secs.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    if (int(secs.size()) < a.min_runs) continue;
    std::vector<double> last(secs.end() - a.min_runs, secs.end());
    std::sort(last.begin(), last.end());
    const double med = last[last.size() / 2];
    if ((last.back() - last.front()) / med < a.target_spread) break;
  }
  std::vector<double> last(secs.end() - std::min<ptrdiff_t>(ptrdiff_t(secs.size()), a.min_runs), secs.end());
  std::sort(last.begin(), last.end());
  const double med = last[last.size() / 2];
  t.median_mrays = double(rays) / med * 1e-6;
  t.spread = (last.back() - last.front()) / med;
  t.runs = int(secs.size());
  return t;
}

/// One set of rays a method is timed on, with the reference's answers.
struct Kind {
  std::string name;
  std::vector<Ray> rays;
  bool occlusion;
  std::vector<ReferenceHit> ref;
};

}  // namespace rp::cli
