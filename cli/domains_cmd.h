#pragma once
// `raypack domains`: the traffic of data-parallel ray tracing, simulated in one process. The
// scene's triangles are split into spatial domains as ranks that each hold one part would hold
// them, and camera, shadow and diffuse rays are followed from owner to owner; the table says
// how many owners a ray visits and what crosses the network per ray.

#include <string>
#include <vector>

#include "backends/registry.h"

namespace CLI {
class App;
}

namespace rp::cli {

struct DomainsArgs {
  std::string scene;
  std::vector<int> domains{2, 4, 8, 16};
  int size = 512;
  std::string backend = "simd", variant = "default";
  uint64_t seed = 1;
  int threads = 0;
  bool quiet = false;  ///< -q: print nothing

  /// Adds the `domains` subcommand to `app` with these flags.
  CLI::App* add_to(CLI::App& app);
};

/// Prints the traffic per ray for each domain count; returns 0.
int run_domains(const DomainsArgs& args);

}  // namespace rp::cli
