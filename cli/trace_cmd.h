#pragma once
// `raypack trace`: a ray file through one backend, the answers of one query to a file: the
// closest hits (with geometric normals) to a hit file, or whether each ray is occluded, how
// many hits it has, or every hit along it (--query; io/rayfile.h has the files).

#include <string>

#include "backends/registry.h"
#include "mpi/comm.h"

namespace CLI {
class App;
}

namespace rp::cli {

struct TraceArgs {
  std::string scene = "default", rays, output, backend{kDefaultBackend}, variant = "default";
  std::string coherence = "incoherent";
  std::string query = "closest";  ///< --query: closest, occluded, count or all
  std::string time;  ///< --time: "" (the rest pose) or seconds into the scene's animation
  int threads = 0;
  bool quiet = false;

  /// Adds the `trace` subcommand to `app` with these flags.
  CLI::App* add_to(CLI::App& app);
};

/// Traces and writes the hit file (or query file); returns the exit status. Across the ranks of `comm` when
/// there are several: each traces its share of the rays and writes its hits at their place.
int run_trace(const TraceArgs& args, const dist::Comm& comm);

}  // namespace rp::cli
