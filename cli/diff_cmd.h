#pragma once
// `raypack diff`: the same rays through backends A and B (either may be the double-precision
// reference), classified ray by ray against the reference, as a table, JSON and an image.

#include <cstddef>
#include <cstdint>
#include <string>

#include "backends/registry.h"
#include "mpi/comm.h"

namespace CLI {
class App;
}

namespace rp::cli {

struct DiffArgs {
  std::string scene = "default";
  std::string up_axis;  ///< --up-axis: "" (the file's), x, y or z
  std::string time;     ///< --time: "" (the rest pose) or seconds into the scene's animation
  std::string kind = "primary";  ///< generated rays: primary, diffuse or random
  std::string rays;              ///< a ray file instead of generated rays
  size_t count = 1 << 20;
  uint64_t seed = 1;
  std::string a{kDefaultBackend}, b = "simd", variant_a = "default", variant_b = "default";
  std::string coherence;
  double tie_tolerance = 1e-6, t_tolerance = 1e-4;
  bool reference = true;
  std::string json, image;
  double min_agreement = 0;
  int threads = 0;
  bool quiet = false;  ///< print nothing on success

  /// Adds the `diff` subcommand to `app` with these flags.
  CLI::App* add_to(CLI::App& app);
};

/// Runs the diff and writes what was asked; returns 0, or 3 below --min-agreement. Across the
/// ranks of `comm` when there are several: each diffs its share of the rays, and the counts
/// and error statistics are combined into those of one process.
int run_diff(const DiffArgs& args, const dist::Comm& comm);

}  // namespace rp::cli
