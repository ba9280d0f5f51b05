#pragma once
// `raypack bench` and `raypack chart`: every backend method on identical rays, speed beside
// accuracy against the double-precision reference, as a table, JSON and gnuplot charts.

#include <string>
#include <vector>

namespace rp::cli {

struct BenchArgs {
  std::vector<std::string> scenes{"default"};
  int size = 512;          ///< primary rays: size x size pixels
  int min_runs = 5, max_runs = 25;
  double target_spread = 0.03;  ///< stop when (max - min) / median of the last min_runs runs is below
  std::string json, chart;
};

/// Runs the benchmark, prints the table, writes JSON and charts when asked. Returns 0.
int run_bench(const BenchArgs& args);

/// Draws `chart` (PNG, plus an SVG beside it, plus <name>-scaling.png/svg) from saved JSON.
void draw_charts(const std::string& json_path, const std::string& chart);

}  // namespace rp::cli
