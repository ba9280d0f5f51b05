#include "cli/bench_updates.h"

#include <algorithm>
#include <cstdio>
#include <string>
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

double build_seconds(const Json& builds, const std::string& key) {
  for (const Json& b : builds)
    if (b["backend"] == key) return b["build_seconds"].get<double>();
  return 0.0;
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
                   const Json& builds, const BenchArgs& a, std::FILE* table) {
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
      const int runs = std::max(1, a.build_runs);
      std::vector<double> secs;
      UpdateReport last;
      for (int r = 1; r <= runs; ++r) {
        motion.step(s, scene, 0.1 * r);
        last = b->update();
        secs.push_back(last.seconds);
      }
      std::sort(secs.begin(), secs.end());
      const double med = secs[secs.size() / 2], spread = med > 0 ? (secs.back() - secs.front()) / med : 0.0;
      const double build = build_seconds(builds, key);
      // The trace speed of the updated structures against structures built over the moved scene.
      const auto fresh = make_backend(v->backend, s, options);
      Json after = Json::array();
      std::string rates;
      for (const Kind& k : kinds) {
        if (k.name != "primary" && k.name != "diffuse") continue;
        const Coherence c = k.name == "primary" ? Coherence::coherent : Coherence::incoherent;
        std::vector<Hit> hits(k.rays.size());
        const Timing updated = time_it(k.rays.size(), a, [&] { intersect_parallel(*b, k.rays, hits, c); });
        const Timing rebuilt = time_it(k.rays.size(), a, [&] { intersect_parallel(*fresh, k.rays, hits, c); });
        after.push_back({{"kind", k.name},
                         {"mrays_updated", updated.median_mrays},
                         {"spread_updated", updated.spread},
                         {"mrays_rebuilt", rebuilt.median_mrays},
                         {"spread_rebuilt", rebuilt.spread},
                         {"ratio", updated.median_mrays / rebuilt.median_mrays}});
        rates += cat(k.name, " ", two_places(updated.median_mrays), " : ", two_places(rebuilt.median_mrays), " (",
                     two_places(updated.median_mrays / rebuilt.median_mrays), "x)  ");
      }
      say(table, "%-18s %-9s %11.5f %7.1f%% %10.4f %8.1fx  %-22s %s\n", key.c_str(), motion.name, med, 100.0 * spread,
          build, med > 0 ? build / med : 0.0, work(last).c_str(), rates.c_str());
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
                     {"after", after}});
    }
  }
  return out;
}

}  // namespace rp::cli
