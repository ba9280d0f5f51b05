#include "cli/bench_cmd.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <regex>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <thread>


#include "analysis/diff.h"
#include "analysis/raygen.h"
#include "analysis/reference.h"
#include "backends/registry.h"
#include "base/error.h"
#include "base/text.h"
#include "cli/args.h"
#include "cli/bench_timing.h"
#include "cli/bench_updates.h"
#include "cli/build_info.h"
#include "cli/pareto.h"
#include "cli/plot.h"
#include "core/thread_limit.h"
#include "io/input_file.h"
#include "io/json_text.h"
#include "io/loaders/load.h"
#include "io/ordered_json.h"
#include "io/output_file.h"
#include "io/rayfile.h"

namespace rp::cli {

namespace {

using Json = nlohmann::ordered_json;

std::string fact(const BackendEntry& e, const std::string& key) {
  for (const auto& [k, v] : e.facts)
    if (k == key) return v;
  return {};
}

/// Every method of the registry (variants × methods); `skipped` gets those this machine would
/// only emulate (Embree's 16-wide packets where its AVX-512 kernels do not run).
std::vector<TraceMethod> methods(std::vector<std::pair<std::string, std::string>>& skipped) {
  std::vector<TraceMethod> m;
  const std::vector<BackendEntry> backends = list_backends();
  for (TraceMethod& t : list_methods()) {
    const BackendEntry& e = *std::ranges::find(backends, t.backend, &BackendEntry::name);
    if (t.backend == "embree" && t.method == "packet16" && fact(e, "native_ray16") != "yes")
      skipped.push_back(
          {t.name, cat("Embree runs its ", fact(e, "isa"), " kernels here: 16-wide packets would be emulated")});
    else
      m.push_back(std::move(t));
  }
  return m;
}

std::string today() {
  char buf[32];
  const std::time_t t = std::time(nullptr);
  std::strftime(buf, sizeof buf, "%Y-%m-%d", std::gmtime(&t));
  return buf;
}

std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  return "unknown CPU";
}

/// The CPU's caches as "L1d 48K, L2 1024K, ..." from sysfs (cpu0), empty when unknown.
Json cpu_caches() {
  Json caches = Json::object();
  for (int i = 0; i < 8; ++i) {
    const std::string dir = cat("/sys/devices/system/cpu/cpu0/cache/index", i, "/");
    std::ifstream level(dir + "level"), type(dir + "type"), size(dir + "size");
    std::string l, t, sz;
    if (!(level >> l && type >> t && size >> sz)) break;
    const std::string name = "L" + l + (t == "Data" ? "d" : t == "Instruction" ? "i" : "");
    caches[name] = sz;
  }
  return caches;
}

/// What a reader needs to put two bench records side by side: the build, the backends'
/// versions and ISAs, the machine.
Json provenance(size_t threads) {
  const BuildInfo& b = build_info();
  Json j;
  j["raypack"] = {{"version", b.version}, {"commit", b.commit}, {"compiler", b.compiler}, {"flags", b.flags},
                  {"build_type", b.build_type}};
  Json backends = Json::object();
  for (const BackendEntry& e : list_backends()) {
    Json f = Json::object();
    for (const auto& [k, v] : e.facts) f[k] = v;
    f["available"] = e.available;
    backends[e.name] = f;
  }
  j["backends"] = backends;
  j["machine"] = {{"cpu", cpu_model()}, {"caches", cpu_caches()}, {"threads", threads},
                  {"hardware_threads", std::thread::hardware_concurrency()}, {"date", today()}};
  return j;
}

/// The kinds measured on `scene`: primary, shadow and diffuse rays (those named in `wanted`,
/// all when empty), or `file_rays` (read from a.ray_file).
std::vector<Kind> ray_kinds(const Scene& scene, const Reference& reference, const BenchArgs& a,
                            const std::vector<Ray>& file_rays) {
  std::vector<Kind> kinds;
  if (!a.ray_file.empty()) {
    kinds.push_back({a.occlusion ? "file-any" : "file", file_rays, a.occlusion, {}});
  } else {
    // Identical rays for every method: primary from the camera, shadow and diffuse from the
    // reference's primary hits (so no backend chooses the rays another is measured on).
    const RaySet primary = primary_rays(scene, a.size, a.size);
    std::vector<ReferenceHit> ref_primary(primary.rays.size());
    reference.intersect(primary.rays, ref_primary);
    std::vector<Hit> primary_hits(primary.rays.size());
    for (size_t i = 0; i < ref_primary.size(); ++i) primary_hits[i] = to_hit(ref_primary[i]);
    const auto want = [&](const char* k) { return a.kinds.empty() || std::ranges::count(a.kinds, k) > 0; };
    if (want("primary")) kinds.push_back({"primary", primary.rays, false, ref_primary});
    if (want("shadow")) kinds.push_back({"shadow", shadow_rays(scene, primary, primary_hits).rays, true, {}});
    if (want("diffuse")) kinds.push_back({"diffuse", diffuse_rays(scene, primary, primary_hits, 7).rays, false, {}});
  }
  for (Kind& k : kinds)
    if (k.ref.empty()) {
      k.ref.resize(k.rays.size());
      reference.intersect(k.rays, k.ref);
    }
  return kinds;
}

/// Build times of one backend variant: the median and spread ((max - min) / median) of
/// `runs` builds after the first (whose time is `first`), so both backends are timed warm
/// (Embree's first build in a process also pays its start-up); the first when runs is 0.
struct BuildTiming {
  double median, spread;
};
BuildTiming time_builds(const TraceMethod& m, const Scene& scene, double first, int runs) {
  if (runs == 0) return {first, 0.0};
  std::vector<double> secs;
  for (int i = 0; i < runs; ++i) secs.push_back(make_backend(m.backend, scene, m.options())->info().build_seconds);
  const auto [median, spread] = median_spread(secs);
  return {median, spread};
}

/// simd's default build against Embree's fastest variant in this run.
void print_build_ratio(std::FILE* out, const Json& js) {
  const Json *simd = nullptr, *fastest = nullptr;
  for (const Json& be : js["backends"]) {
    const std::string name = be["backend"];
    if (name == "simd/default") simd = &be;
    if (name.starts_with("embree/") && (!fastest || be["build_seconds"] < (*fastest)["build_seconds"])) fastest = &be;
  }
  if (!simd || !fastest) return;
  const double s = (*simd)["build_seconds"], e = (*fastest)["build_seconds"];
  say(out, "build: simd/default %.4f s, fastest Embree (%s) %.4f s: %.2fx\n", s,
      (*fastest)["backend"].get<std::string>().c_str(), e, e > 0 ? s / e : 0.0);
}

/// The fastest simd and Embree method per kind of rays, and their ratio (the figure the
/// project is judged by: hand-written against Embree's best on the same rays).
void print_best(std::FILE* out, const Json& js, const std::vector<Kind>& kinds) {
  bool header = false;
  for (const Kind& k : kinds) {
    const Json* best[2] = {nullptr, nullptr};
    for (const Json& r : js["results"]) {
      if (r["kind"] != k.name) continue;
      const int side = r["backend"].get<std::string>().starts_with("simd/") ? 0 : 1;
      if (!best[side] || r["mrays_per_s"].get<double>() > (*best[side])["mrays_per_s"].get<double>()) best[side] = &r;
    }
    if (!best[0] || !best[1]) continue;
    if (!header)
      say(out, "\n%-8s %-32s %10s   %-32s %10s %8s\n", "rays", "best simd", "Mrays/s", "best embree", "Mrays/s",
          "ratio");
    header = true;
    const double s = (*best[0])["mrays_per_s"].get<double>(), e = (*best[1])["mrays_per_s"].get<double>();
    say(out, "%-8s %-32s %10.2f   %-32s %10.2f %7.2fx\n", k.name.c_str(),
        (*best[0])["method"].get<std::string>().c_str(), s, (*best[1])["method"].get<std::string>().c_str(), e, s / e);
  }
}

}  // namespace

CLI::App* BenchArgs::add_to(CLI::App& app) {
  CLI::App* c = app.add_subcommand("bench", "Every backend method on identical rays: speed beside accuracy");
  c->add_option("--scene", scenes, "Scene: 'default' or a file (repeatable)")->capture_default_str();
  add_up_axis_option(c, up_axis);
  c->add_option("--size", size, "Primary rays: SIZE x SIZE pixels")->check(CLI::Range(8, 8192))->capture_default_str();
  c->add_option("--min-runs", min_runs, "Runs over which the spread is judged")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  c->add_option("--max-runs", max_runs, "Most runs per measurement")->check(CLI::Range(1, 1000))->capture_default_str();
  c->add_option("--build-runs", build_runs,
                "Builds timed per backend variant after the first (median reported; 0: the first build only)")
      ->check(CLI::Range(0, 100))
      ->capture_default_str();
  c->add_option("--method", method_filter,
                "Only the methods whose name (backend/variant:method) matches this regular expression");
  c->add_option("--kind", kinds, "Only these ray kinds: primary, shadow, diffuse (repeatable)");
  c->add_option("--rays", ray_file, "Time the rays of this ray file (one --scene) instead of the generated kinds");
  c->add_flag("--any-hit", occlusion, "With --rays: time any-hit (occlusion) queries, not closest hits");
  c->add_flag("--updates,!--no-updates", updates,
              "Also time update() after every mesh is deformed and every instance moved (default: on), against "
              "the build, and the trace speed after it against a new build");
  c->add_option("--json", json, "Write the results as JSON");
  c->add_option("--chart", chart, "Also draw the charts (.png or .svg by the extension, with gnuplot)");
  c->add_option("--stability", stability,
                "With --chart: a `raypack stability --json` file; also draw the speed-against-exactness chart FILE-pareto")
      ->check(CLI::ExistingFile);
  add_threads_option(c, threads);
  add_quiet_flag(c, quiet);
  return c;
}

CLI::App* ChartArgs::add_to(CLI::App& app) {
  CLI::App* c = app.add_subcommand("chart", "Redraw the charts of a saved `raypack bench --json` file");
  c->add_option("json", json, "The bench JSON")->required();
  c->add_option("-o,--output", output, "Chart (.png or .svg by the extension; a -scaling chart is written beside it)")
      ->capture_default_str();
  c->add_option("--stability", stability,
                "A `raypack stability --json` file: also draw the speed-against-exactness chart <output>-pareto")
      ->check(CLI::ExistingFile);
  add_quiet_flag(c, quiet);
  return c;
}

namespace {

/// Refuses, before any work, charts (and their -scaling and -pareto companions) or a JSON
/// output that cannot be written or that name an input or each other.
void check_bench_outputs(std::vector<NamedFile> inputs, const std::string& json_flag, const std::string& json,
                         const std::string& chart_flag, const std::string& chart, bool pareto) {
  std::vector<NamedFile> outputs{{json_flag, json}};
  if (!chart.empty()) {
    outputs.push_back({chart_flag, chart});
    outputs.push_back({chart_flag + " (its -scaling chart)", companion_chart(chart, "-scaling")});
    if (pareto) outputs.push_back({chart_flag + " (its -pareto chart)", companion_chart(chart, "-pareto")});
  }
  check_distinct_files(inputs, outputs);
  for (const NamedFile& o : outputs) {
    if (o.path.empty()) continue;
    check_file_name(o.flag, o.path, o.flag == json_flag ? check_output : check_chart_output);
  }
}

}  // namespace

int run_chart(const ChartArgs& a) {
  check_bench_outputs({{"json", a.json}, {"--stability", a.stability}}, "", "", "-o", a.output, !a.stability.empty());
  std::string files;
  for (const std::string& f : draw_charts(a.json, a.output, a.stability)) files += (files.empty() ? "" : ", ") + f;
  say(a.quiet ? nullptr : stderr, "raypack: wrote %s\n", files.c_str());
  return 0;
}

int run_bench(const BenchArgs& a) {
  if (a.max_runs < a.min_runs) throw UsageError(cat("--max-runs: ", a.max_runs, " is below --min-runs ", a.min_runs));
  if (!a.stability.empty() && a.chart.empty()) throw UsageError("--stability: draws a chart, so it needs --chart");
  if (!a.stability.empty()) read_hard_failures(a.stability);  // a bad file is refused before the timing
  const ThreadLimit limit(a.threads);
  std::FILE* const table = a.quiet ? nullptr : stdout;
  const auto usage = [](bool ok, auto&&... message) {
    if (!ok) throw UsageError(cat(message...));
  };
  usage(a.size >= 8 && a.size <= 8192, "bench: --size ", a.size, " is out of range (8..8192)");
  usage(a.ray_file.empty() || a.scenes.size() == 1, "bench: --rays needs exactly one --scene (the rays' scene), got ",
        a.scenes.size());
  usage(!a.occlusion || !a.ray_file.empty(), "bench: --any-hit applies to --rays only");
  if (!a.ray_file.empty()) check_file_name("--rays", a.ray_file, check_ray_file_name);
  {
    std::vector<NamedFile> inputs{{"--rays", a.ray_file}, {"--stability", a.stability}};
    for (const std::string& s : a.scenes) inputs.push_back({"--scene", s});
    check_bench_outputs(inputs, "--json", a.json, "--chart", a.chart, !a.stability.empty());
  }
  const std::optional<int> up = parse_up_axis(a.up_axis);
  for (const std::string& k : a.kinds)
    usage(k == "primary" || k == "shadow" || k == "diffuse", "bench: --kind '", k, "' is not one of primary, shadow, diffuse");
  const size_t threads = size_t(max_threads());

  std::vector<std::pair<std::string, std::string>> skipped;
  std::vector<TraceMethod> chosen;
  {
    std::regex filter;
    try {
      filter = std::regex(a.method_filter.empty() ? std::string(".") : a.method_filter);
    } catch (const std::regex_error& e) {
      throw UsageError(cat("bench: --method '", one_line(a.method_filter), "' is not a regular expression: ", e.what()));
    }
    std::string names;
    for (const TraceMethod& m : methods(skipped)) {
      names += (names.empty() ? "" : ", ") + m.name;
      if (std::regex_search(m.name, filter)) chosen.push_back(m);
    }
    std::erase_if(skipped, [&](const auto& sk) { return !std::regex_search(sk.first, filter); });
    usage(!chosen.empty(), "bench: --method '", one_line(a.method_filter), "' matches none of: ", names);
  }

  Json out = provenance(threads);
  out["skipped_methods"] = Json::array();
  for (const auto& [name, why] : skipped) out["skipped_methods"].push_back({{"method", name}, {"reason", why}});
  const std::vector<Ray> file_rays = a.ray_file.empty() ? std::vector<Ray>{} : read_rays(a.ray_file);
  out["scenes"] = Json::array();
  for (const std::string& path : a.scenes) {
    const Scene scene = load_scene(path, up);
    const std::string name = path == "default" ? "default" : std::filesystem::path(path).filename().string();
    const Reference reference(scene);
    std::vector<Kind> kinds = ray_kinds(scene, reference, a, file_rays);

    Json js;
    js["scene"] = name;
    js["path"] = path;
    if (!a.ray_file.empty()) js["rays_file"] = a.ray_file;
    js["triangles"] = scene.triangle_count();
    js["primitives"] = scene.prim_count();
    js["backends"] = Json::array();
    js["results"] = Json::array();
    say(table, "\n%s: %u triangles, %u primitives;", name.c_str(), scene.triangle_count(), scene.prim_count());
    for (const Kind& k : kinds) say(table, " %zu %s", k.rays.size(), k.name.c_str());
    say(table, " rays; %zu threads\n", threads);
    say(table, "%-32s %-8s %10s %8s %5s %12s   %s\n", "method", "rays", "Mrays/s", "spread", "runs", "mismatch",
        "hit/miss wrong-prim t-error");
    std::vector<std::string> recorded;
    for (const TraceMethod& m : chosen) {
      const std::string backend_key = m.backend + "/" + m.variant;
      const std::unique_ptr<Backend> b =
          make_backend(m.backend, scene, m.options());
      if (std::ranges::count(recorded, backend_key) == 0) {
        const BuildTiming bt = time_builds(m, scene, b->info().build_seconds, a.build_runs);
        js["backends"].push_back({{"backend", backend_key},
                                  {"build_seconds", bt.median},
                                  {"build_spread", bt.spread},
                                  {"build_runs", a.build_runs},
                                  {"build_seconds_first", b->info().build_seconds},
                                  {"bytes", b->info().bytes},
                                  {"bytes_per_prim", double(b->info().bytes) / std::max(1.0, double(scene.prim_count()))}});
        recorded.push_back(backend_key);
      }
      for (Kind& k : kinds) {
        const std::vector<Ray>& rays = k.rays;
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
            ref_hits[i] = to_hit(k.ref[i]);
          const DiffResult d = diff_hits(scene, rays, hits, ref_hits, {}, {});
          count = d.count;
        }
        const double n = std::max<double>(1.0, double(rays.size()));
        const double mismatch = double(count[2] + count[3] + count[4]) / n;
        say(table, "%-32s %-8s %10.2f %7.1f%% %5d %12.3g   %zu %zu %zu\n", m.name.c_str(), k.name.c_str(),
            t.median_mrays, 100.0 * t.spread, t.runs, mismatch, count[2], count[3], count[4]);
        if (table) std::fflush(table);
        js["results"].push_back({{"method", m.name},
                                 {"backend", backend_key},
                                 {"coherence", m.coherence == Coherence::coherent ? "coherent" : "incoherent"},
                                 {"coherent_method", m.coherence == Coherence::coherent ? m.method : ""},
                                 {"incoherent_method", m.coherence == Coherence::coherent ? "" : m.method},
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
    print_best(table, js, kinds);
    say(table, "\n%-16s %12s %8s %12s %14s %12s\n", "backend", "build s", "spread", "first s", "bytes", "bytes/prim");
    for (const Json& be : js["backends"])
      say(table, "%-16s %12.4f %7.1f%% %12.4f %14zu %12.1f\n", be["backend"].get<std::string>().c_str(),
          be["build_seconds"].get<double>(), 100.0 * be["build_spread"].get<double>(),
          be["build_seconds_first"].get<double>(), be["bytes"].get<size_t>(), be["bytes_per_prim"].get<double>());
    print_build_ratio(table, js);
    if (a.updates) js["updates"] = bench_updates(scene, chosen, kinds, a, table);
    out["scenes"].push_back(js);
  }
  for (const auto& [name, why] : skipped) say(table, "\n%s: not run: %s\n", name.c_str(), why.c_str());
  if (!a.json.empty()) write_file(a.json, out.dump(2) + "\n");
  if (!a.chart.empty()) draw_charts(out, a.chart, a.stability);
  return 0;
}

namespace {

/// Bench results that cannot be charted (the message names no file; the caller adds it).
struct BenchFileError : Error {
  using Error::Error;
};

/// Refuses results without scenes, or without a single timed result to draw.
void check_bench_results(const Json& j) {
  if (!(j.is_object() && j.contains("scenes") && j["scenes"].is_array() && !j["scenes"].empty()))
    throw BenchFileError("not a raypack bench file (no \"scenes\")");
  for (const Json& sc : j["scenes"])
    if (sc.contains("results") && sc["results"].is_array() && !sc["results"].empty()) return;
  throw BenchFileError("no results to chart (every scene's \"results\" is empty)");
}

}  // namespace

std::vector<std::string> draw_charts(const std::string& json_path, const std::string& chart,
                                     const std::string& stability) {
  const std::string text = read_file(json_path);
  check_json_depth(json_path, text);
  Json j;
  try {
    j = parse_ordered_json(text);
  } catch (const Json::exception& e) {
    throw Error(cat(json_path, ": not a raypack bench file: ", json_reason(e.what())));
  }
  try {
    check_bench_results(j);
    return draw_charts(j, chart, stability);
  } catch (const Json::exception& e) {  // a value of the wrong type or a missing key
    throw Error(cat(json_path, ": not a raypack bench file: ", json_reason(e.what())));
  } catch (const BenchFileError& e) {
    throw Error(cat(json_path, ": ", e.what()));
  }
}

std::vector<std::string> draw_charts(const Json& j, const std::string& chart, const std::string& stability) {
  check_bench_results(j);
  chart_format(chart);  // an unknown format is refused before anything is drawn
  const std::string scaling = companion_chart(chart, "-scaling");
  constexpr double kFloor = 1e-7;  // where a zero mismatch rate is drawn
  const Json& machine = j.contains("machine") ? j["machine"] : Json::object();
  const std::string title = cat("cpu ", machine.value("cpu", std::string("?")), ", ", machine.value("threads", 0),
                                " threads, ", machine.value("date", std::string("?")));
  const Json& scenes = j["scenes"];
  const size_t n_scenes = scenes.size();
  // The ray kinds the file has results for (primary, shadow, diffuse, or a ray file's), in order.
  std::vector<std::string> kinds;
  for (const Json& sc : scenes)
    for (const Json& r : sc["results"])
      if (std::ranges::count(kinds, r["kind"].get<std::string>()) == 0) kinds.push_back(r["kind"].get<std::string>());
  const size_t n_kinds = kinds.size();

  // Speed against accuracy: one panel per scene and kind, a point per method (an inline data
  // block "rate drawn-mismatch-rate" each), every method in the same style in every panel and named
  // once in a legend column on the right; a scene without results of a kind leaves its panel
  // empty.
  std::vector<std::string> methods;  // in order of first appearance
  for (const Json& sc : scenes)
    for (const Json& r : sc["results"])
      if (std::ranges::count(methods, r["method"].get<std::string>()) == 0) methods.push_back(r["method"].get<std::string>());
  constexpr int kPanelW = 500, kPanelH = 380, kLegendW = 280, kTitleH = 60;
  const int width = kPanelW * int(n_kinds) + kLegendW, height = kPanelH * int(n_scenes) + kTitleH;
  std::ostringstream g;
  for (size_t s = 0; s < n_scenes; ++s)
    for (size_t k = 0; k < n_kinds; ++k)
      for (const Json& r : scenes[s]["results"])
        if (r["kind"] == kinds[k]) {
          const size_t m = size_t(std::ranges::find(methods, r["method"].get<std::string>()) - methods.begin());
          g << "$s" << s << "k" << k << "m" << m << " << EOD\n"
            << r["mrays_per_s"].get<double>() << ' ' << std::max(kFloor, r["mismatch_rate"].get<double>()) << "\nEOD\n";
        }
  g << "set multiplot title " << gnuplot_string("raypack bench: speed against accuracy (" + title + ")") << " font ',12'\n";
  g << "set logscale y\nset yrange [" << kFloor / 3 << ":1]\nset format y '%.0e'\nset grid\nset key off\n";
  g << "set ytics add ('0 (floor)' " << kFloor << ")\nset xlabel 'Mrays/s'\nset ylabel 'mismatch rate vs reference'\n";
  g << "set offsets graph 0.1, graph 0.1, 0, 0\n";
  for (size_t s = 0; s < n_scenes; ++s)
    for (size_t k = 0; k < n_kinds; ++k) {
      std::string plot;
      for (const Json& r : scenes[s]["results"])
        if (r["kind"] == kinds[k]) {
          const size_t m = size_t(std::ranges::find(methods, r["method"].get<std::string>()) - methods.begin());
          plot += cat(plot.empty() ? "plot " : ", ", "$s", s, "k", k, "m", m, " using 1:2 with points ps 1.5",
                      point_style(m), " notitle");
        }
      if (plot.empty()) continue;
      g << "set origin " << double(kPanelW) * double(k) / width << ","
        << double(kPanelH) * double(n_scenes - 1 - s) / height << "\nset size " << double(kPanelW) / width << ","
        << double(kPanelH) / height << "\n";
      g << "set title " << gnuplot_string(scenes[s]["scene"].get<std::string>() + ": " + kinds[k] + " rays") << "\n";
      g << plot << "\n";
    }
  g << legend_cell(methods, double(kPanelW) * double(n_kinds) / width, 0.0, double(kLegendW) / width,
                   double(kPanelH) * double(n_scenes) / height);
  g << "unset multiplot\n";
  plot_to(chart, cat(width, ",", height), g.str());

  // Cost against scene size: the diffuse-ray rate against triangles, a line per method.
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
  std::vector<std::string> written{chart, scaling};
  if (!stability.empty()) written.push_back(draw_pareto(j, stability, chart));
  return written;
}

}  // namespace rp::cli
