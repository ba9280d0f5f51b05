#include "io/output_file.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <climits>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include "base/error.h"

namespace rp {

namespace {

// ---- temporary files the signal handler removes ----------------------------------------------
// A fixed table, so the handler touches no allocator: a slot is claimed (state 0 to 1), filled, then
// published (2); the handler unlinks every published path. unlink, signal and raise are
// async-signal-safe.

constexpr int kSlots = 64;
struct Slot {
  std::atomic<int> state{0};  ///< 0 free, 1 being filled, 2 holds a path
  char path[PATH_MAX];
};
Slot g_slots[kSlots];
static_assert(std::atomic<int>::is_always_lock_free);

int claim_slot(const std::string& path) {
  if (path.size() >= PATH_MAX) return -1;
  for (int i = 0; i < kSlots; ++i) {
    int expected = 0;
    if (!g_slots[i].state.compare_exchange_strong(expected, 1)) continue;
    std::memcpy(g_slots[i].path, path.c_str(), path.size() + 1);
    g_slots[i].state.store(2);
    return i;
  }
  return -1;  // more than kSlots outputs at once: this one is removed by its destructor only
}

void release_slot(int i) {
  if (i >= 0) g_slots[i].state.store(0);
}

std::atomic<uint64_t> g_serial{0};

std::string temp_name(const std::string& file_name) {
  return cat(".raypack-", ::getpid(), "-", g_serial.fetch_add(1), "-", file_name);
}

/// Removes from `folder` the temporaries of `file_name` that a run killed before it could
/// clean up left behind (SIGKILL, a crash, a node lost): ".raypack-<pid>-<n>-<file_name>"
/// files whose maker holds no lock on them any more (every OutputFile holds one on its
/// temporary while it lives) and whose pid is no live process here.
void remove_stale_temporaries(const std::filesystem::path& folder, const std::string& file_name) {
  namespace fs = std::filesystem;
  std::error_code ec;
  for (fs::directory_iterator it(folder.empty() ? fs::path(".") : folder, ec), end; !ec && it != end;
       it.increment(ec)) {
    const std::string name = it->path().filename().string();
    // .raypack-<digits>-<digits>-<file_name>
    if (!name.starts_with(".raypack-") || !name.ends_with("-" + file_name)) continue;
    const std::string_view middle = std::string_view(name).substr(9, name.size() - 9 - file_name.size() - 1);
    const size_t dash = middle.find('-');
    if (dash == std::string_view::npos || dash == 0 || dash + 1 == middle.size() ||
        middle.find_first_not_of("0123456789-") != std::string_view::npos ||
        middle.find('-', dash + 1) != std::string_view::npos)
      continue;
    const long pid = std::strtol(std::string(middle.substr(0, dash)).c_str(), nullptr, 10);
    if (pid == long(::getpid()) || (pid > 0 && (::kill(pid_t(pid), 0) == 0 || errno == EPERM))) continue;
    const int fd = ::open(it->path().c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) continue;
    struct stat st {};
    if (::fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && ::flock(fd, LOCK_EX | LOCK_NB) == 0)
      ::unlink(it->path().c_str());
    ::close(fd);
  }
}

/// Writes all n bytes to fd; returns errno on failure, 0 on success.
int write_all(int fd, const char* data, size_t n) {
  while (n > 0) {
    const ssize_t w = ::write(fd, data, n);
    if (w < 0) {
      if (errno == EINTR) continue;
      return errno;
    }
    data += w;
    n -= size_t(w);
  }
  return 0;
}

/// What the handler prints before it ends the process (empty: nothing); %s is the signal.
char g_signal_message[512];

extern "C" void remove_temporaries_and_reraise(int sig) {
  bool removed = false;
  for (Slot& s : g_slots)
    if (s.state.load() == 2) removed |= ::unlink(s.path) == 0;
  if (g_signal_message[0] != '\0') {
    const char* name = sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : "SIGHUP";
    const char* at = std::strstr(g_signal_message, "%s");
    const char* outcome = removed ? "; unfinished outputs were removed\n" : "; no output was left unfinished\n";
    write_all(STDERR_FILENO, g_signal_message, size_t(at - g_signal_message));
    write_all(STDERR_FILENO, name, std::strlen(name));
    write_all(STDERR_FILENO, at + 2, std::strlen(at + 2));
    write_all(STDERR_FILENO, outcome, std::strlen(outcome));
  }
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

}  // namespace

OutputFile::OutputFile(const std::string& path) : path_(path) {
  namespace fs = std::filesystem;
  if (path.empty()) throw Error("cannot write to an empty file name");
  struct stat st {};
  bool device = false;
  mode_t replace_mode = 0;
  bool replaces = false;
  if (::stat(path.c_str(), &st) == 0) {
    if (S_ISDIR(st.st_mode)) fail("it is a directory");
    if (S_ISREG(st.st_mode)) {
      struct stat link {};
      if (::lstat(path.c_str(), &link) == 0 && S_ISLNK(link.st_mode)) {
        char* resolved = ::realpath(path.c_str(), nullptr);
        if (!resolved) fail(cat("cannot resolve the symbolic link: ", std::strerror(errno)));
        target_ = resolved;
        std::free(resolved);
      } else {
        target_ = path;
      }
      replaces = true;
      replace_mode = st.st_mode & 07777;
    } else {
      device = true;  // character or block device, FIFO, socket: written into, never replaced
    }
  } else {
    const int e = errno;
    struct stat link {};
    if (e == ENOENT && ::lstat(path.c_str(), &link) == 0 && S_ISLNK(link.st_mode))
      fail("it is a symbolic link to a missing file (not followed)");
    if (e != ENOENT) fail(std::strerror(e));
    target_ = path;
  }

  // The temporary: beside the file it replaces, or in the temporary folder for a device.
  fs::path folder;
  std::string file_name;
  if (device) {
    std::error_code ec;
    const fs::path dir = fs::temp_directory_path(ec);
    folder = ec ? fs::path("/tmp") : dir;
    file_name = fs::path(path).filename().string();
    if (file_name.empty()) file_name = "output";
  } else {
    const fs::path t(target_);
    folder = t.parent_path();
    file_name = t.filename().string();
  }
  remove_stale_temporaries(folder, file_name);
  temp_ = (folder / temp_name(file_name)).string();
  slot_ = claim_slot(temp_);
  fd_ = ::open(temp_.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
  if (fd_ < 0) {
    const int e = errno;
    release_slot(slot_);
    slot_ = -1;
    fail(std::strerror(e));
  }
  // Held while this lives: what marks the temporary as in use (remove_stale_temporaries).
  ::flock(fd_, LOCK_EX | LOCK_NB);
  if (replaces) ::fchmod(fd_, replace_mode);  // best effort: the new file keeps the old one's mode
}

OutputFile::~OutputFile() {
  if (fd_ >= 0) ::close(fd_);
  if (!committed_ && !temp_.empty()) ::unlink(temp_.c_str());
  release_slot(slot_);
}

void OutputFile::fail(const std::string& reason) const { throw Error(cat(path_, ": cannot write: ", reason)); }

void OutputFile::write(const void* data, size_t n) {
  if (committed_) fail("already committed");
  if (const int e = write_all(fd_, static_cast<const char*>(data), n)) fail(std::strerror(e));
}

void OutputFile::commit() {
  if (committed_) fail("already committed");
  if (target_.empty()) {
    // A device: copy the finished temporary into it, then drop the temporary.
    const int out = ::open(path_.c_str(), O_WRONLY | O_NOCTTY | O_CLOEXEC);
    if (out < 0) fail(std::strerror(errno));
    char buffer[1 << 16];
    off_t at = 0;
    for (;;) {
      const ssize_t n = ::pread(fd_, buffer, sizeof buffer, at);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) {
        const int e = errno;
        ::close(out);
        fail(std::strerror(e));
      }
      if (n == 0) break;
      if (const int e = write_all(out, buffer, size_t(n))) {
        ::close(out);
        fail(std::strerror(e));
      }
      at += n;
    }
    if (::close(out) != 0 && errno != EINTR) fail(std::strerror(errno));
    ::close(fd_);
    fd_ = -1;
    ::unlink(temp_.c_str());
  } else {
    if (::fsync(fd_) != 0) fail(std::strerror(errno));
    const int fd = fd_;
    fd_ = -1;
    if (::close(fd) != 0) fail(std::strerror(errno));
    if (::rename(temp_.c_str(), target_.c_str()) != 0) fail(std::strerror(errno));
  }
  committed_ = true;
  release_slot(slot_);
  slot_ = -1;
}

int pwrite_all(int fd, const void* data, size_t n, uint64_t offset) {
  const char* p = static_cast<const char*>(data);
  while (n > 0) {
    const ssize_t w = ::pwrite(fd, p, n, off_t(offset));
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return w < 0 ? errno : EIO;
    p += w;
    n -= size_t(w);
    offset += uint64_t(w);
  }
  return 0;
}

void write_file(const std::string& path, std::string_view bytes) {
  OutputFile out(path);
  out.write(bytes.data(), bytes.size());
  out.commit();
}

void check_output(const std::string& path) { OutputFile probe(path); }

namespace {

/// What makes two names one file: the device and inode of a file that exists; else its
/// folder, resolved, and its name.
struct FileKey {
  bool exists = false;
  bool device = false;  ///< a character device (/dev/null), which outputs may share
  dev_t dev = 0;
  ino_t ino = 0;
  std::string where;

  explicit FileKey(const std::string& path) {
    namespace fs = std::filesystem;
    struct stat st {};
    if (::stat(path.c_str(), &st) == 0) {
      exists = true;
      device = S_ISCHR(st.st_mode);
      dev = st.st_dev;
      ino = st.st_ino;
      return;
    }
    const fs::path p(path);
    const fs::path folder = p.parent_path().empty() ? fs::path(".") : p.parent_path();
    std::error_code ec;
    const fs::path real = fs::canonical(folder, ec);
    where = ((ec ? fs::absolute(folder, ec).lexically_normal() : real) / p.filename()).string();
  }
  bool same(const FileKey& o) const {
    return exists == o.exists && (exists ? dev == o.dev && ino == o.ino : where == o.where);
  }
};

}  // namespace

void check_distinct(const std::vector<NamedFile>& inputs, const std::vector<NamedFile>& outputs) {
  std::vector<std::pair<const NamedFile*, FileKey>> seen;
  for (const NamedFile& f : inputs)
    if (!f.path.empty() && f.path != "default" && f.path != "-") seen.emplace_back(&f, FileKey(f.path));
  const size_t n_inputs = seen.size();
  for (const NamedFile& f : outputs) {
    if (f.path.empty()) continue;
    const FileKey key(f.path);
    for (size_t i = 0; i < seen.size(); ++i) {
      if (!key.same(seen[i].second) || (i >= n_inputs && key.device)) continue;
      throw Error(cat(f.flag, " ", f.path, ": is the same file as ", i < n_inputs ? "the input " : "the output ",
                      seen[i].first->flag, " ", seen[i].first->path));
    }
    seen.emplace_back(&f, key);
  }
}

void set_signal_message(std::string_view message) {
  RP_CHECK(message.empty() || (message.size() < sizeof g_signal_message && message.find("%s") != std::string_view::npos),
           "signal message: at most ", sizeof g_signal_message - 1, " bytes, with %s for the signal");
  std::memcpy(g_signal_message, message.data(), message.size());
  g_signal_message[message.size()] = '\0';
}

void install_signal_cleanup() {
  struct sigaction sa {};
  sa.sa_handler = remove_temporaries_and_reraise;
  sigemptyset(&sa.sa_mask);
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) ::sigaction(sig, &sa, nullptr);
  // A closed pipe on standard output is an error to report (and clean up after), not a
  // silent death by SIGPIPE.
  std::signal(SIGPIPE, SIG_IGN);
}

}  // namespace rp
