#pragma once
// The raypack command of this build, run as a user runs it, for the tests of the command.

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "tests/support/build_paths.h"
#include "tests/support/shell.h"

namespace rp::test {

/// Runs `raypack <args>` through the shell, after `prefix` (shell commands such as a ulimit).
inline ShellResult run_raypack(const std::string& args, const std::string& prefix = "") {
  return run_shell(prefix + std::string(kRaypackExe) + " " + args);
}

/// The bytes of file `p` (empty when it cannot be read).
inline std::string file_bytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

}  // namespace rp::test
