#pragma once
// `raypack stability`: failure rates per method × ray family (analysis/stability.h) as a table,
// JSON and a chart.

#include <cstdint>
#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace rp::cli {

struct StabilityArgs {
  std::string scene = "default";
  uint32_t count = 4096;  ///< rays per family
  uint64_t seed = 1;
  double t_tolerance = 1e-4;
  std::vector<std::string> methods;   ///< backend/variant; empty: every variant worth comparing
  std::vector<std::string> families;  ///< empty: all
  std::string json, chart;
  bool list = false;  ///< print the families and methods, run nothing
  int threads = 0;
  bool quiet = false;  ///< print nothing on success

  /// Adds the `stability` subcommand to `app` with these flags.
  CLI::App* add_to(CLI::App& app);
};

/// Runs the families, prints the table, writes JSON and the chart when asked. Returns 0.
int run_stability(const StabilityArgs& args);

}  // namespace rp::cli
