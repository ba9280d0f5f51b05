#pragma once
// `raypack bench` and `raypack chart`: every backend method on identical rays, speed beside
// accuracy against the double-precision reference, as a table, JSON and gnuplot charts.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace rp::cli {

struct BenchArgs {
  std::vector<std::string> scenes{"default"};
  std::string up_axis;  ///< --up-axis: "" (each file's), x, y or z, for every scene
  int size = 512;          ///< primary rays: size x size pixels
  int min_runs = 5, max_runs = 25;
  int build_runs = 5;  ///< builds timed per backend variant after a first, untimed one (median reported)
  double target_spread = 0.03;  ///< stop when (max - min) / median of the last min_runs runs is below
  std::string method_filter;      ///< ECMAScript regex searched in method labels; empty: every method
  std::vector<std::string> kinds;  ///< primary, shadow, diffuse: the ray kinds timed (empty: all)
  std::string ray_file;           ///< time these rays (one scene) instead of the generated kinds
  bool occlusion = false;         ///< with ray_file: any-hit queries instead of closest hits
  bool updates = true;            ///< also time Backend::update() after motion (bench_updates.h)
  std::string json, chart;
  std::string stability;  ///< a `raypack stability --json` file: also draw the Pareto chart (pareto.h)
  int threads = 0;
  bool quiet = false;  ///< print nothing on success

  /// Adds the `bench` subcommand to `app` with these flags.
  CLI::App* add_to(CLI::App& app);
};

/// `raypack chart`: the charts of a saved bench JSON file.
struct ChartArgs {
  std::string json, output = "chart.png";
  std::string stability;  ///< a `raypack stability --json` file: also draw the Pareto chart (pareto.h)
  bool quiet = false;

  /// Adds the `chart` subcommand to `app` with these flags.
  CLI::App* add_to(CLI::App& app);
};

/// Runs the benchmark, prints the table, writes JSON and charts when asked. Returns 0.
int run_bench(const BenchArgs& args);

/// Draws `chart` (rate against mismatch rate, a panel per scene and ray kind) and, beside
/// it, <name>-scaling.<ext> (rate against triangle count), both in the format of the
/// extension (.png or .svg), from a saved bench JSON file, and <name>-pareto.<ext> (draw_pareto)
/// when `stability` names a stability JSON file. Throws rp::Error naming the file. Returns the
/// files written.
std::vector<std::string> draw_charts(const std::string& json_path, const std::string& chart,
                                     const std::string& stability = {});

/// Draws the charts of `args`; returns 0.
int run_chart(const ChartArgs& args);

/// The same from the bench results in memory.
std::vector<std::string> draw_charts(const nlohmann::ordered_json& results, const std::string& chart,
                                     const std::string& stability = {});

}  // namespace rp::cli
