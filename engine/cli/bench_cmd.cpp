#include "engine/cli/bench_cmd.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include <tbb/global_control.h>
#include <tbb/info.h>

#include "backends/registry.h"
#include "engine/cli/plot.h"
#include "engine/diff.h"
#include "engine/error.h"
#include "engine/input_file.h"
#include "engine/json_text.h"
#include "engine/output_file.h"
#include "engine/loaders/load.h"
#include "engine/raygen.h"
#include "engine/reference.h"

namespace rp::cli {

namespace {

using Json = nlohmann::ordered_json;

/// One way of tracing: a backend variant and a coherence hint (packets or single rays).
struct Method {
  std::string label, backend, variant;
  Coherence coherence;
};

std::vector<Method> methods() {
  std::vector<Method> m;
  for (const BackendEntry& e : list_backends()) {
    if (!e.available) continue;
    if (e.name == "simd") {
      m.push_back({"simd packet", "simd", "default", Coherence::coherent});
      m.push_back({"simd single", "simd", "default", Coherence::incoherent});
      m.push_back({"simd watertight packet", "simd", "watertight", Coherence::coherent});
      m.push_back({"simd watertight single", "simd", "watertight", Coherence::incoherent});
    } else if (e.name == "embree") {
      m.push_back({"embree rtcIntersect8", "embree", "default", Coherence::coherent});
      m.push_back({"embree rtcIntersect1", "embree", "default", Coherence::incoherent});
      m.push_back({"embree robust 8", "embree", "robust", Coherence::coherent});
      m.push_back({"embree robust 1", "embree", "robust", Coherence::incoherent});
    }
  }
  return m;
}

std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  return "unknown CPU";
}

std::string today() {
  char buf[32];
  const std::time_t t = std::time(nullptr);
  std::strftime(buf, sizeof buf, "%Y-%m-%d", std::gmtime(&t));
  return buf;
}

/// Timing runs until the spread of the last min_runs is below the target (or max_runs).
struct Timing {
  double median_mrays = 0, spread = 0;  ///< spread: (max - min) / median over the runs kept
  int runs = 0;
};

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

}  // namespace

int run_bench(const BenchArgs& a) {
  RP_CHECK(a.size >= 8 && a.size <= 8192, "bench: --size ", a.size, " is out of range (8..8192)");
  const size_t threads = tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism);
  Json out;
  out["machine"] = {{"cpu", cpu_model()}, {"threads", threads}, {"date", today()}};
  out["scenes"] = Json::array();
  for (const std::string& path : a.scenes) {
    const Scene scene = load_scene(path);
    const std::string name = path == "default" ? "default" : std::filesystem::path(path).filename().string();
    // Identical rays for every method: primary from the camera, shadow and diffuse from the
    // reference's primary hits (so no backend chooses the rays another is measured on).
    const RaySet primary = primary_rays(scene, a.size, a.size);
    const Reference reference(scene);
    std::vector<ReferenceHit> ref_primary(primary.rays.size());
    reference.intersect(primary.rays, ref_primary);
    std::vector<Hit> primary_hits(primary.rays.size());
    for (size_t i = 0; i < ref_primary.size(); ++i)
      if (ref_primary[i].hit())
        primary_hits[i] = {float(ref_primary[i].t), ref_primary[i].prim_id, float(ref_primary[i].u), float(ref_primary[i].v)};
    const RaySet shadow = shadow_rays(scene, primary, primary_hits);
    const RaySet diffuse = diffuse_rays(scene, primary, primary_hits, 7);
    struct Kind {
      const char* name;
      const RaySet* set;
      bool occlusion;
      std::vector<ReferenceHit> ref;
    };
    Kind kinds[3] = {{"primary", &primary, false, ref_primary}, {"shadow", &shadow, true, {}}, {"diffuse", &diffuse, false, {}}};
    for (Kind& k : kinds)
      if (k.ref.empty()) {
        k.ref.resize(k.set->rays.size());
        reference.intersect(k.set->rays, k.ref);
      }

    Json js;
    js["scene"] = name;
    js["path"] = path;
    js["triangles"] = scene.triangle_count();
    js["primitives"] = scene.prim_count();
    js["backends"] = Json::array();
    js["results"] = Json::array();
    std::printf("\n%s: %u triangles, %u primitives; %zu primary, %zu shadow, %zu diffuse rays; %zu threads\n",
                name.c_str(), scene.triangle_count(), scene.prim_count(), primary.rays.size(), shadow.rays.size(),
                diffuse.rays.size(), threads);
    std::printf("%-22s %-8s %10s %8s %5s %12s   %s\n", "method", "rays", "Mrays/s", "spread", "runs", "mismatch",
                "hit/miss wrong-prim t-error");
    std::string last_backend;
    for (const Method& m : methods()) {
      const std::string backend_key = m.backend + "/" + m.variant;
      const std::unique_ptr<Backend> b = make_backend(m.backend, scene, {.variant = m.variant, .device_config = {}, .coherent_method = {}});
      if (backend_key != last_backend) {
        js["backends"].push_back({{"backend", backend_key}, {"build_seconds", b->info().build_seconds},
                                  {"bytes", b->info().bytes},
                                  {"bytes_per_prim", double(b->info().bytes) / std::max(1.0, double(scene.prim_count()))}});
        last_backend = backend_key;
      }
      for (Kind& k : kinds) {
        const std::vector<Ray>& rays = k.set->rays;
        std::vector<Hit> hits(rays.size());
        std::vector<uint8_t> occ(rays.size());
        const Timing t = time_it(rays.size(), a, [&] {
          if (k.occlusion) occluded_parallel(*b, rays, occ, m.coherence);
          else intersect_parallel(*b, rays, hits, m.coherence);
        });
        // Accuracy on the same rays against the reference.
        std::array<size_t, kDiffClasses> count{};
        if (k.occlusion) {
          for (size_t i = 0; i < rays.size(); ++i) ++count[size_t(bool(occ[i]) == k.ref[i].hit() ? 0 : 2)];
        } else {
          std::vector<Hit> ref_hits(rays.size());
          for (size_t i = 0; i < rays.size(); ++i)
            if (k.ref[i].hit()) ref_hits[i] = {float(k.ref[i].t), k.ref[i].prim_id, float(k.ref[i].u), float(k.ref[i].v)};
          const DiffResult d = diff_hits(scene, rays, hits, ref_hits, {}, {});
          count = d.count;
        }
        const double n = std::max<double>(1.0, double(rays.size()));
        const double mismatch = double(count[2] + count[3] + count[4]) / n;
        std::printf("%-22s %-8s %10.2f %7.1f%% %5d %12.3g   %zu %zu %zu\n", m.label.c_str(), k.name, t.median_mrays,
                    100.0 * t.spread, t.runs, mismatch, count[2], count[3], count[4]);
        js["results"].push_back({{"method", m.label},
                                 {"backend", backend_key},
                                 {"kind", k.name},
                                 {"rays", rays.size()},
                                 {"mrays_per_s", t.median_mrays},
                                 {"spread", t.spread},
                                 {"runs", t.runs},
                                 {"mismatch_rate", mismatch},
                                 {"hit_miss", count[2]},
                                 {"wrong_prim", count[3]},
                                 {"t_error", count[4]},
                                 {"ties", count[1]}});
      }
    }
    std::printf("\n%-16s %12s %14s %12s\n", "backend", "build s", "bytes", "bytes/prim");
    for (const Json& be : js["backends"])
      std::printf("%-16s %12.4f %14zu %12.1f\n", be["backend"].get<std::string>().c_str(), be["build_seconds"].get<double>(),
                  be["bytes"].get<size_t>(), be["bytes_per_prim"].get<double>());
    out["scenes"].push_back(js);
  }
  if (!a.json.empty()) write_file(a.json, out.dump(2) + "\n");
  if (!a.chart.empty()) draw_charts(out, a.chart);
  return 0;
}

void draw_charts(const std::string& json_path, const std::string& chart) {
  const std::string text = read_file(json_path);
  check_json_depth(json_path, text);
  Json j;
  try {
    j = Json::parse(text);
  } catch (const Json::exception& e) {
    throw Error(cat(json_path, ": not a raypack bench file: ", json_reason(e.what())));
  }
  try {
    draw_charts(j, chart);
  } catch (const Json::exception& e) {  // a value of the wrong type or a missing key
    throw Error(cat(json_path, ": not a raypack bench file: ", json_reason(e.what())));
  }
}

void draw_charts(const Json& j, const std::string& chart) {
  namespace fs = std::filesystem;
  if (!(j.is_object() && j.contains("scenes") && j["scenes"].is_array() && !j["scenes"].empty()))
    throw Error("not a raypack bench file (no \"scenes\")");
  chart_format(chart);  // an unknown format is refused before anything is drawn
  const fs::path file(chart);
  const std::string scaling = ((file.parent_path() / file.stem()).string() + "-scaling") + file.extension().string();
  constexpr double kFloor = 1e-7;  // where a zero mismatch rate is drawn
  const char* kinds[3] = {"primary", "shadow", "diffuse"};
  const Json& machine = j.contains("machine") ? j["machine"] : Json::object();
  const std::string title = cat("cpu ", machine.value("cpu", std::string("?")), ", ", machine.value("threads", 0),
                                " threads, ", machine.value("date", std::string("?")));
  const Json& scenes = j["scenes"];
  const size_t n_scenes = scenes.size();

  // Speed against accuracy: one panel per scene and kind, each an inline data block of
  // "Mrays/s drawn-rate label".
  std::ostringstream g;
  for (size_t s = 0; s < n_scenes; ++s)
    for (int k = 0; k < 3; ++k) {
      g << "$s" << s << "k" << k << " << EOD\n";
      for (const Json& r : scenes[s]["results"])
        if (r["kind"] == kinds[k])
          g << r["mrays_per_s"].get<double>() << ' ' << std::max(kFloor, r["mismatch_rate"].get<double>()) << " \""
            << gnuplot_label(r["method"].get<std::string>()) << "\"\n";
      g << "EOD\n";
    }
  g << "set multiplot layout " << n_scenes << ",3 title "
    << gnuplot_string("raypack bench: speed against accuracy (" + title + ")") << " font ',12'\n";
  g << "set logscale y\nset yrange [" << kFloor / 3 << ":1]\nset format y '%.0e'\nset grid\nset key off\n";
  g << "set ytics add ('0 (floor)' " << kFloor << ")\nset xlabel 'Mrays/s'\nset ylabel 'mismatch rate vs reference'\n";
  for (size_t s = 0; s < n_scenes; ++s)
    for (int k = 0; k < 3; ++k) {
      g << "set title " << gnuplot_string(scenes[s]["scene"].get<std::string>() + ": " + kinds[k] + " rays") << "\n";
      g << "set offsets graph 0.1, graph 0.45, 0, 0\n";
      g << "plot $s" << s << "k" << k << " using 1:2:($0+1) with points pt 7 ps 1.5 lc variable, '' using 1:2:3 "
        << "with labels rotate by 40 left offset 0.4,0.5 font ',8'\n";
    }
  g << "unset multiplot\n";
  plot_to(chart, cat(1500, ",", 380 * int(n_scenes) + 60), g.str());

  // Cost against scene size: Mrays/s on diffuse rays against triangles, a line per method.
  std::ostringstream c;
  std::vector<std::string> labels;
  for (const Json& r : scenes[0]["results"])
    if (r["kind"] == "diffuse") labels.push_back(r["method"].get<std::string>());
  for (size_t m = 0; m < labels.size(); ++m) {
    c << "$m" << m << " << EOD\n";
    for (const Json& sc : scenes)
      for (const Json& r : sc["results"])
        if (r["kind"] == "diffuse" && r["method"] == labels[m])
          c << std::max<double>(1.0, sc["triangles"].get<double>()) << ' ' << r["mrays_per_s"].get<double>() << "\n";
    c << "EOD\n";
  }
  c << "set title " << gnuplot_string("raypack bench: cost against scene size, diffuse rays; " + title) << "\n";
  c << "set logscale x\nset grid\nset key outside right\nset xlabel 'triangles'\nset ylabel 'Mrays/s'\n";
  if (labels.empty()) c << "plot 1 notitle\n";
  for (size_t m = 0; m < labels.size(); ++m)
    c << (m ? ", " : "plot ") << "$m" << m << " using 1:2 with linespoints title " << gnuplot_string(labels[m])
      << (m + 1 == labels.size() ? "\n" : "");
  plot_to(scaling, "900,500", c.str());
}

}  // namespace rp::cli
