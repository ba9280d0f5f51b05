#pragma once
// `raypack info` (a scene's counts, bounds and bytes, and each backend's structure) and
// `raypack backends` (what the registry offers on this machine).

#include <string>

namespace CLI {
class App;
}

namespace rp::cli {

struct InfoArgs {
  std::string scene = "default";
  std::string time;  ///< --time: "" (the rest pose) or seconds into the scene's animation
  bool no_backends = false;
  bool quiet = false;  ///< -q: print nothing (the scene is loaded and the backends built all the same)

  /// Adds the `info` subcommand to `app` with these flags.
  CLI::App* add_to(CLI::App& app);
};

/// Prints the scene's figures (posed at --time) with its animation's and, unless
/// --no-backends, each backend's; returns 0.
int run_info(const InfoArgs& args);

/// Adds the `backends` subcommand to `app`.
CLI::App* add_backends_command(CLI::App& app);

/// Prints every backend with its variants, coherent methods and facts; returns 0.
int run_backends();

}  // namespace rp::cli
