#pragma once
// Output helpers shared by the CLI commands that write files and charts: atomic writes, and
// gnuplot run on a script whose output goes to a temporary file renamed into place.

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "engine/error.h"

namespace rp::cli {

/// Writes `target` through `write(tmp)` to a temporary name beside it, then renames, so the
/// target is never left half-written.
template <typename Write>
void write_atomically(const std::string& target, Write&& write) {
  namespace fs = std::filesystem;
  const fs::path t(target);
  const fs::path tmp = t.parent_path() / (".raypack-" + std::to_string(::getpid()) + "-" + t.filename().string());
  std::error_code ec;
  if (!write(tmp.string())) {
    fs::remove(tmp, ec);
    throw Error(cat("cannot write '", target, "'"));
  }
  fs::rename(tmp, t, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw Error(cat("cannot write '", target, "': ", ec.message()));
  }
}

/// Fails with the install hint when gnuplot is not on PATH.
inline void require_gnuplot() {
  RP_CHECK(std::system("command -v gnuplot >/dev/null 2>&1") == 0,
           "chart: gnuplot is not installed (apt-get install gnuplot-nox; .ci/setup.sh does it)");
}

/// Runs gnuplot with `terminal` on `script` (everything after `set terminal` and `set output`)
/// to draw `file` atomically; `work` is a scratch folder. Throws with gnuplot's first error line.
inline void plot_to(const std::string& terminal, const std::string& script, const std::string& file,
                    const std::filesystem::path& work) {
  write_atomically(file, [&](const std::string& tmp) {
    const std::filesystem::path gp = work / "plot.gp", err = work / "err.txt";
    std::ofstream(gp) << "set terminal " << terminal << "\nset output '" << tmp << "'\n" << script;
    if (std::system(cat("gnuplot '", gp.string(), "' 2>'", err.string(), "'").c_str()) == 0) return true;
    std::ifstream e(err);
    std::string first;
    std::getline(e, first);
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw Error(cat("chart: gnuplot failed for '", file, "': ", first));
  });
}

}  // namespace rp::cli
