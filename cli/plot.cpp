#include "cli/plot.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include "base/error.h"
#include "io/output_file.h"

extern char** environ;

namespace rp::cli {

namespace {

/// A descriptor closed on scope exit.
struct Fd {
  int fd = -1;
  ~Fd() { close(); }
  void close() {
    if (fd >= 0) ::close(fd);
    fd = -1;
  }
};

/// A child process, waited for; one left running when an error unwinds is killed first.
struct Child {
  pid_t pid = -1;
  ~Child() {
    if (pid > 0) {
      ::kill(pid, SIGKILL);
      wait();
    }
  }
  /// Waits for the child to end; its status for WIFEXITED and the rest.
  int wait() {
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0)
      if (errno != EINTR) break;
    pid = -1;
    return status;
  }
};

/// The first line of what gnuplot wrote to `fd` (an unlinked scratch file) with something on
/// it besides blanks and gnuplot's "^" marker; control characters become '?'.
std::string first_error_line(int fd) {
  char buffer[1024];
  const ssize_t n = ::pread(fd, buffer, sizeof buffer, 0);
  const std::string_view text(buffer, n > 0 ? size_t(n) : 0);
  for (size_t start = 0; start < text.size();) {
    size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    std::string_view l = text.substr(start, end - start);
    start = end + 1;
    while (!l.empty() && (l.front() == ' ' || l.front() == '\t' || l.front() == '\r')) l.remove_prefix(1);
    while (!l.empty() && (l.back() == ' ' || l.back() == '\t' || l.back() == '\r')) l.remove_suffix(1);
    if (l.empty() || l == "^") continue;
    std::string line(l);
    for (char& c : line)
      if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = '?';
    return line;
  }
  return "no message";
}

}  // namespace

ChartFormat chart_format(const std::string& file) {
  std::string ext = std::filesystem::path(file).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".png") return ChartFormat::png;
  if (ext == ".svg") return ChartFormat::svg;
  throw Error(cat("chart: '", file, "': unknown chart format '", ext, "' (.png or .svg)"));
}

void require_gnuplot() {
  const char* path = std::getenv("PATH");
  const std::string dirs = path ? path : "/usr/bin:/bin";
  for (size_t start = 0; start <= dirs.size();) {
    size_t end = dirs.find(':', start);
    if (end == std::string::npos) end = dirs.size();
    const std::string dir = end > start ? dirs.substr(start, end - start) : ".";
    if (::access((dir + "/gnuplot").c_str(), X_OK) == 0) return;
    start = end + 1;
  }
  throw Error("chart: gnuplot is not installed (apt-get install gnuplot-nox; .ci/setup.sh does it)");
}

std::string companion_chart(const std::string& chart, const std::string& suffix) {
  const std::filesystem::path file(chart);
  return ((file.parent_path() / file.stem()).string() + suffix) + file.extension().string();
}

void check_chart_output(const std::string& file) {
  chart_format(file);
  require_gnuplot();
  check_output(file);
}

std::string gnuplot_string(std::string_view text) {
  std::string out = "'";
  for (const char c : text) {
    if (c == '\'') out += "''";
    else if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) out += '?';
    else out += c;
  }
  return out + "'";
}

std::string gnuplot_label(std::string_view text) {
  std::string out;
  for (const char c : text)
    out += (static_cast<unsigned char>(c) < 0x20 || c == 0x7f || c == '"' || c == '\\') ? '?' : c;
  return out;
}

std::string point_style(size_t i) {
  static constexpr const char* kColours[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd",
                                             "#8c564b", "#e377c2", "#17becf", "#7f7f7f", "#bcbd22"};
  static constexpr int kPoints[] = {7, 5, 9, 11, 13, 6, 4, 8, 10, 12, 1, 2, 3};
  return cat(" pt ", kPoints[i % std::size(kPoints)], " lc rgb '", kColours[i % std::size(kColours)], "'");
}

std::string legend_cell(const std::vector<std::string>& labels, double x, double y, double w, double h) {
  std::string g = cat("set origin ", x, ",", y, "\nset size ", w, ",", h, "\n");
  g += "unset title\nunset xlabel\nunset ylabel\nunset border\nunset tics\nunset grid\nunset logscale\n";
  g += "set xrange [0:1]\nset yrange [0:1]\nset key inside center center vertical Left reverse samplen 1 font ',10'\n";
  for (size_t i = 0; i < labels.size(); ++i)
    g += cat(i ? ", " : "plot ", "NaN with points ps 1.5", point_style(i), " title ", gnuplot_string(labels[i]));
  return g + (labels.empty() ? "plot NaN notitle\n" : "\n");
}

void plot_to(const std::string& file, const std::string& size, const std::string& script) {
  const ChartFormat format = chart_format(file);
  require_gnuplot();
  OutputFile out(file);
  const std::string program =
      cat("set terminal ", format == ChartFormat::png ? "pngcairo" : "svg", " size ", size, " noenhanced\n", script,
          "\nunset output\n");

  // gnuplot's standard error goes to an unlinked scratch file: read after it exits, it can
  // never fill a pipe while the script is still being written.
  Fd err;
  {
    std::error_code ec;
    std::filesystem::path dir = std::filesystem::temp_directory_path(ec);
    if (ec) dir = "/tmp";
    err.fd = ::open(dir.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);  // never has a name
    if (err.fd < 0) {  // a file system without O_TMPFILE: a named file, unlinked at once
      std::string name = (dir / "raypack-gnuplot-XXXXXX").string();
      err.fd = ::mkostemp(name.data(), O_CLOEXEC);
      if (err.fd < 0) throw Error(cat("chart: cannot make a scratch file: ", std::strerror(errno)));
      ::unlink(name.c_str());
    }
  }
  // The script goes in through one pipe and the chart comes back through another, both
  // served by one poll loop; the chart is written here by OutputFile, which checks every
  // write (gnuplot does not report a full disk).
  int in_fds[2], out_fds[2];
  if (::pipe2(in_fds, O_CLOEXEC) != 0) throw Error(cat("chart: cannot make a pipe: ", std::strerror(errno)));
  Fd script_read{in_fds[0]}, script_write{in_fds[1]};
  if (::pipe2(out_fds, O_CLOEXEC) != 0) throw Error(cat("chart: cannot make a pipe: ", std::strerror(errno)));
  Fd chart_read{out_fds[0]}, chart_write{out_fds[1]};

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, script_read.fd, STDIN_FILENO);
  posix_spawn_file_actions_adddup2(&actions, chart_write.fd, STDOUT_FILENO);
  posix_spawn_file_actions_adddup2(&actions, err.fd, STDERR_FILENO);
  char arg0[] = "gnuplot";
  char* argv[] = {arg0, nullptr};
  Child gnuplot;
  const int spawned = ::posix_spawnp(&gnuplot.pid, "gnuplot", &actions, nullptr, argv, environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) {
    gnuplot.pid = -1;
    throw Error(cat("chart: cannot run gnuplot: ", std::strerror(spawned)));
  }
  ::close(script_read.fd);
  script_read.fd = -1;
  ::close(chart_write.fd);
  chart_write.fd = -1;
  ::fcntl(script_write.fd, F_SETFL, O_NONBLOCK);

  // A gnuplot that stops reading early (an error) makes a script write fail with EPIPE
  // (SIGPIPE is ignored by the CLI), which its exit status then explains.
  const char* p = program.data();
  size_t left = program.size();
  if (left == 0) script_write.close();
  char buffer[1 << 16];
  while (script_write.fd >= 0 || chart_read.fd >= 0) {
    pollfd fds[2];
    nfds_t n = 0;
    if (script_write.fd >= 0) fds[n++] = {script_write.fd, POLLOUT, 0};
    if (chart_read.fd >= 0) fds[n++] = {chart_read.fd, POLLIN, 0};
    if (::poll(fds, n, -1) < 0) {
      if (errno == EINTR) continue;
      throw Error(cat("chart: waiting for gnuplot: ", std::strerror(errno)));
    }
    for (nfds_t i = 0; i < n; ++i) {
      if (fds[i].revents == 0) continue;
      if (fds[i].fd == script_write.fd) {
        const ssize_t w = ::write(script_write.fd, p, left);
        if (w < 0 && (errno == EINTR || errno == EAGAIN)) continue;
        if (w < 0) {
          script_write.close();
          continue;
        }
        p += w;
        left -= size_t(w);
        if (left == 0) script_write.close();
      } else {
        const ssize_t r = ::read(chart_read.fd, buffer, sizeof buffer);
        if (r < 0 && errno == EINTR) continue;
        if (r <= 0) {
          chart_read.close();
          continue;
        }
        out.write(buffer, size_t(r));
      }
    }
  }
  const int status = gnuplot.wait();
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || left > 0)
    throw Error(cat("chart: gnuplot failed for '", file, "': ", first_error_line(err.fd)));
  out.commit();
}

}  // namespace rp::cli
