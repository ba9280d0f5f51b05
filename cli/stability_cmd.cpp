#include "cli/stability_cmd.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>

#include "analysis/stability.h"
#include "backends/registry.h"
#include "base/error.h"
#include "base/text.h"
#include "cli/args.h"
#include "cli/plot.h"
#include "io/loaders/load.h"
#include "io/output_file.h"

namespace rp::cli {

namespace {

/// The chart users look for: failure rate against translation magnitude per backend method
/// (left), and the share of rays leaving a surface that hit it again, raw and offset (right).
/// The format follows the extension of `chart` (.png or .svg).
void draw_chart(const std::vector<stability::Result>& results, const std::string& scene, const std::string& chart) {
  constexpr double kFloor = 1e-5;  // where a zero rate is drawn
  // series name -> data lines "k rate"
  std::map<std::string, std::ostringstream> left, right;
  for (const stability::Result& r : results) {
    if (!r.has_exponent) continue;
    const double rate = std::max(kFloor, r.counts.rate());
    if (r.family == "translated") left[r.method] << r.exponent << ' ' << rate << '\n';
    if ((r.family == "leaving_raw" || r.family == "leaving_offset") && r.param.rfind("translated", 0) == 0 &&
        r.method.find('/') != std::string::npos && r.method.rfind("triangle", 0) != 0)
      right[r.family.substr(8) + " " + r.method] << r.exponent << ' ' << rate << '\n';
  }
  std::ostringstream g;
  int block = 0;
  std::ostringstream plots;
  auto panel = [&](const char* title, const char* ylabel, std::map<std::string, std::ostringstream>& series) {
    plots << "set title " << gnuplot_string(title) << "\nset ylabel " << gnuplot_string(ylabel) << "\n";
    if (series.empty()) {
      plots << "plot 2 notitle\n";  // an empty panel (nothing selected), axes only
      return;
    }
    plots << "plot ";
    int i = 0;
    for (auto& [name, data] : series) {
      g << "$d" << block << " << EOD\n" << data.str() << "EOD\n";  // inline data, no files
      plots << (i++ ? ", " : "") << "$d" << block++ << " using 1:2 with linespoints lw 2 title " << gnuplot_string(name);
    }
    plots << "\n";
  };
  panel("failures on the moved scene (leaks, false hits, t errors)", "failure rate", left);
  panel("rays leaving a surface that hit it again", "self-hit rate", right);
  g << "set multiplot layout 1,2 title " << gnuplot_string("raypack stability: " + scene) << " font ',12'\n";
  g << "set logscale y\nset yrange [" << kFloor / 2 << ":1.5]\nset format y '%.0e'\nset grid\n";
  g << "set ytics add ('0' " << kFloor << ")\nset xlabel 'translation 10^k: k'\nset xrange [-0.3:7.3]\n";
  g << "set key below font ',9' maxrows 3\n" << plots.str() << "unset multiplot\n";
  plot_to(chart, "1400,620", g.str());
}

}  // namespace

CLI::App* StabilityArgs::add_to(CLI::App& app) {
  CLI::App* c = app.add_subcommand("stability", "Failure rates per method and ray family where intersection methods fail");
  c->add_option("--scene", scene, "Scene: 'default' or a file; its meshes give the mesh families")
      ->capture_default_str();
  c->add_option("--count", count, "Rays per family")->check(CLI::Range(1, 1 << 22))->capture_default_str();
  c->add_option("--seed", seed, "Seed of every family's rays")->capture_default_str();
  c->add_option("--t-tolerance", t_tolerance, "Relative t difference counted as an error")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  c->add_option("--method", methods,
                "Backend method backend/variant:method (repeatable; default embree/default:single, "
                "embree/robust:single, simd/default:stream, simd/watertight:stream)");
  c->add_option("--family", families, "Run only this family (repeatable; see --list)");
  c->add_flag("--list", list, "List the families and scalar methods");
  c->add_option("--json", json, "Write the results as JSON");
  c->add_option("--chart", chart, "Draw the chart (PNG and SVG beside it, with gnuplot)");
  add_threads_option(c, threads);
  add_quiet_flag(c, quiet);
  return c;
}

int run_stability(const StabilityArgs& a) {
  if (a.list) {
    std::printf("families:\n");
    for (const auto& [name, what] : stability::family_names()) std::printf("  %-15s %s\n", name.c_str(), what.c_str());
    std::printf("scalar methods:\n ");
    for (const std::string& m : stability::scalar_methods()) std::printf(" %s", m.c_str());
    std::printf("\n");
    return 0;
  }
  for (const std::string& f : a.families) {
    std::string names;
    bool known = false;
    for (const auto& [name, what] : stability::family_names()) {
      known |= name == f;
      names += (names.empty() ? "" : ", ") + name;
    }
    if (!known) throw UsageError(cat("--family: unknown family '", f, "' (", names, ")"));
  }
  check_distinct_files({{"--scene", a.scene}}, {{"--json", a.json}, {"--chart", a.chart}});
  if (!a.json.empty()) check_file_name("--json", a.json, check_output);
  if (!a.chart.empty()) check_file_name("--chart", a.chart, check_chart_output);
  const ThreadLimit limit(a.threads);
  stability::Options o;
  o.rays = a.count;
  o.seed = a.seed;
  o.t_tolerance = a.t_tolerance;
  o.families = a.families;
  // Methods: the ones asked for, else every backend variant whose triangle test differs, each
  // with its default incoherent method (the families' rays are not coherent).
  const std::vector<TraceMethod> available = list_methods();
  const auto find = [&](const std::string& name) { return std::ranges::find(available, name, &TraceMethod::name); };
  if (!a.methods.empty()) {
    o.backends = a.methods;
    for (const std::string& m : o.backends)
      if (find(m) == available.end()) {
        for (const BackendEntry& e : list_backends())
          if (!e.available && m.starts_with(e.name + "/"))
            throw UsageError(
                cat("--method: backend '", e.name, "' is not available on this machine: ", e.unavailable_reason));
        std::string names;
        for (const TraceMethod& t : available) names += (names.empty() ? "" : ", ") + t.name;
        throw UsageError(cat("--method: unknown method '", one_line(m), "' (", names, ")"));
      }
  } else {
    const std::vector<std::string> defaults = o.backends;
    o.backends.clear();
    for (const std::string& m : defaults)
      if (find(m) != available.end())
        o.backends.push_back(m);
      else
        say(a.quiet ? nullptr : stderr, "raypack: stability: %s is not available here, skipped\n", m.c_str());
  }
  o.make_backend = [find](const std::string& method, const Scene& scene) {
    const TraceMethod& m = *find(method);
    return stability::MethodBackend{make_backend(m.backend, scene, m.options()), m.coherence};
  };
  if (!a.quiet)
    o.progress = [](const std::string& family) { std::fprintf(stderr, "raypack: stability: %s\n", family.c_str()); };
  const Scene scene = load_scene(a.scene);
  const auto start = std::chrono::steady_clock::now();
  const std::vector<stability::Result> results = stability::run(scene, o);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::FILE* const out = a.quiet ? nullptr : stdout;
  say(out, "raypack stability: scene %s, %u rays per family, seed %llu, t tolerance %g (relative)\n",
      a.scene.c_str(), a.count, (unsigned long long)a.seed, a.t_tolerance);
  if (out) stability::print_table(out, results);
  say(out, "(%.1f s)\n", seconds);
  if (!a.json.empty()) write_file(a.json, stability::to_json(results, a.scene, o));
  if (!a.chart.empty()) {
    draw_chart(results, a.scene, a.chart);
    say(a.quiet ? nullptr : stderr, "raypack: wrote %s\n", a.chart.c_str());
  }
  return 0;
}

}  // namespace rp::cli
