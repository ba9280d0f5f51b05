#include "cli/bench_updates.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "analysis/motion.h"
#include "base/error.h"
#include "cli/args.h"

namespace rp::cli {

namespace {

using Json = nlohmann::ordered_json;

/// A moderate motion: each step moves vertices and instances by up to about 1% of their
/// box's diagonal.
constexpr double kAmplitude = 0.01;

struct Motion {
  const char* name;
  bool (*applies)(const Scene&);
  void (*step)(Scene&, const Scene& rest, double phase);
};

const Motion kMotions[] = {
    {"vertices", [](const Scene& s) { return s.triangle_count() > 0; },
     [](Scene& s, const Scene& rest, double phase) { wobble_meshes(s, rest, kAmplitude, phase); }},
    {"instances", [](const Scene& s) { return !s.instances().empty(); },
     [](Scene& s, const Scene& rest, double phase) { jostle_instances(s, rest, kAmplitude, phase); }},
};

/// Seconds of one call of f.
template <typename F>
double seconds_of(F&& f) {
  const auto start = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// Two traces of the same rays timed in alternation (a then b, then b then a, ...), so that a
/// shared machine's drift falls on both: the median of each and of the per-pair speed ratio
/// a / b, with the ratios' lowest and highest.
struct PairTiming {
  double mrays_a = 0, mrays_b = 0, ratio = 0, ratio_lo = 0, ratio_hi = 0;
};

template <typename A, typename B>
PairTiming time_pair(size_t rays, int pairs, A&& a, B&& b) {
  a();
  b();  // warm-up, untimed
  std::vector<double> ta, tb, ratio;
  for (int i = 0; i < pairs; ++i) {
    double x, y;
    if (i % 2 == 0) {
      x = seconds_of(a);
      y = seconds_of(b);
    } else {
      y = seconds_of(b);
      x = seconds_of(a);
    }
    ta.push_back(x);
    tb.push_back(y);
    ratio.push_back(y / x);
  }
  PairTiming t;
  t.mrays_a = double(rays) / median_spread(ta).first * 1e-6;
  t.mrays_b = double(rays) / median_spread(tb).first * 1e-6;
  t.ratio = median_spread(ratio).first;
  t.ratio_lo = ratio.front();
  t.ratio_hi = ratio.back();
  return t;
}

std::string two_places(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f", x);
  return buf;
}

std::string work(const UpdateReport& r) {
  std::string w = cat(r.refits, " refit", r.refits == 1 ? "" : "s");
  if (r.rebuilds) w += cat(", ", r.rebuilds, " rebuilt");
  if (r.top) w += ", top";
  return w;
}

}  // namespace

Json bench_updates(const Scene& scene, std::span<const TraceMethod> chosen, std::span<const Kind> kinds,
                   const BenchArgs& a, std::FILE* table) {
  Json out = Json::array();
  std::vector<const TraceMethod*> variants;
  for (const TraceMethod& m : chosen)
    if (std::ranges::none_of(variants,
                             [&](const TraceMethod* v) { return v->backend == m.backend && v->variant == m.variant; }))
      variants.push_back(&m);
  say(table, "\n%-18s %-9s %11s %8s %10s %9s  %-22s %s\n", "update", "motion", "update s", "spread", "build s",
      "build/upd", "work", "Mrays/s updated : rebuilt");
  for (const TraceMethod* v : variants) {
    const std::string key = v->backend + "/" + v->variant;
    for (const Motion& motion : kMotions) {
      if (!motion.applies(scene)) continue;
      Scene s = scene;
      BackendOptions options;
      options.variant = v->variant;
      const auto b = make_backend(v->backend, s, options);
      motion.step(s, scene, 0.0);
      b->update();  // warm-up, untimed
      // Each frame's update, then a build over the same frame: the two in alternation.
      const int runs = std::max(1, a.build_runs);
      std::vector<double> secs, builds_now, over;
      UpdateReport last;
      std::unique_ptr<Backend> fresh;
      for (int r = 1; r <= runs; ++r) {
        motion.step(s, scene, 0.1 * r);
        last = b->update();
        fresh.reset();
        fresh = make_backend(v->backend, s, options);
        secs.push_back(last.seconds);
        builds_now.push_back(fresh->info().build_seconds);
        over.push_back(last.seconds > 0 ? builds_now.back() / last.seconds : 0.0);
      }
      const auto [med, spread] = median_spread(secs);
      const double build = median_spread(builds_now).first, build_over = median_spread(over).first;
      // The trace speed of the updated structures against structures built over the moved scene.
      Json after = Json::array();
      std::string rates;
      for (const Kind& k : kinds) {
        if (k.name != "primary" && k.name != "diffuse") continue;
        const Coherence c = k.name == "primary" ? Coherence::coherent : Coherence::incoherent;
        std::vector<Hit> hits(k.rays.size());
        const PairTiming t = time_pair(
            k.rays.size(), std::max(a.min_runs, 7), [&] { intersect_parallel(*b, k.rays, hits, c); },
            [&] { intersect_parallel(*fresh, k.rays, hits, c); });
        after.push_back({{"kind", k.name},
                         {"mrays_updated", t.mrays_a},
                         {"mrays_rebuilt", t.mrays_b},
                         {"ratio", t.ratio},
                         {"ratio_lo", t.ratio_lo},
                         {"ratio_hi", t.ratio_hi}});
        rates +=
            cat(k.name, " ", two_places(t.mrays_a), " : ", two_places(t.mrays_b), " (", two_places(t.ratio), "x)  ");
      }
      say(table, "%-18s %-9s %11.5f %7.1f%% %10.4f %8.1fx  %-22s %s\n", key.c_str(), motion.name, med, 100.0 * spread,
          build, build_over, work(last).c_str(), rates.c_str());
      if (table) std::fflush(table);
      out.push_back({{"backend", key},
                     {"motion", motion.name},
                     {"amplitude", kAmplitude},
                     {"update_seconds", med},
                     {"update_spread", spread},
                     {"update_runs", runs},
                     {"refits", last.refits},
                     {"rebuilds", last.rebuilds},
                     {"top", last.top},
                     {"build_seconds", build},
                     {"build_over_update", build_over},
                     {"after", after}});
    }
  }
  return out;
}

}  // namespace rp::cli
