#pragma once
// Running a command line as a user would, for the tests of the raypack binary.

#include <sys/wait.h>

#include <cstdio>
#include <string>

namespace rp::test {

struct ShellResult {
  int status;          ///< the exit status; -1 when the command did not exit (a signal) or could not start
  std::string output;  ///< its standard output and standard error
};

/// Runs `command` through the shell, standard error into the captured output.
inline ShellResult run_shell(const std::string& command) {
  FILE* p = popen((command + " 2>&1").c_str(), "r");
  if (!p) return {-1, "popen failed"};
  std::string out;
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
  const int st = pclose(p);
  return {WIFEXITED(st) ? WEXITSTATUS(st) : -1, out};
}

}  // namespace rp::test
