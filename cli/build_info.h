#pragma once
// What the raypack binary was built from, for benchmark records (cli/build_info.cmake).

#include <string>

namespace rp::cli {

struct BuildInfo {
  std::string version;     ///< the project version, e.g. "0.1.0"
  std::string commit;      ///< the git commit, "+uncommitted changes" when the tree differed; "unknown" outside git
  std::string compiler;    ///< e.g. "GNU 12.2.0"
  std::string flags;       ///< the C++ flags of the build type, and the simd kernels' ISA flags
  std::string build_type;  ///< e.g. "Release"
};

const BuildInfo& build_info();

}  // namespace rp::cli
