#pragma once
// `raypack points`: the closest point of a scene's surface to each point of a point file, with
// its distance, primitive, geometry and instance, and with --signed the signed distance and
// inside (core/queries.h; io/pointfile.h has the files).

#include <string>

#include "backends/registry.h"

namespace CLI {
class App;
}

namespace rp::cli {

struct PointsArgs {
  std::string scene, points, output, backend{kDefaultBackend}, variant = "default";
  std::string time;        ///< --time: "" (the rest pose) or seconds into the scene's animation
  bool with_sign = false;  ///< --signed
  int threads = 0;
  bool quiet = false;

  /// Adds the `points` subcommand to `app` with these flags.
  CLI::App* add_to(CLI::App& app);
};

/// Answers the closest-point queries and writes the file; returns the exit status.
int run_points(const PointsArgs& args);

}  // namespace rp::cli
