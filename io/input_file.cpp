#include "io/input_file.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <new>

#include "base/error.h"

namespace rp {

namespace {

/// What a non-regular file is, for messages.
const char* kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a file";
}

/// Reads n bytes at the descriptor's position into dst; false at a premature end.
bool read_fully(int fd, char* dst, size_t n, const std::string& path) {
  while (n > 0) {
    const ssize_t got = ::read(fd, dst, n);
    if (got < 0) {
      if (errno == EINTR) continue;
      throw Error(cat(path, ": cannot read: ", std::strerror(errno)));
    }
    if (got == 0) return false;
    dst += got;
    n -= size_t(got);
  }
  return true;
}

/// Standard input to its end, at most kMaxStandardInputBytes.
std::string read_standard_input() {
  std::string text;
  char buffer[1 << 16];
  for (;;) {
    const ssize_t n = ::read(STDIN_FILENO, buffer, sizeof buffer);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw Error(cat("standard input: cannot read: ", std::strerror(errno)));
    }
    if (n == 0) return text;
    if (text.size() + size_t(n) > kMaxStandardInputBytes)
      throw Error(cat("standard input: more than ", kMaxStandardInputBytes,
                      " bytes; larger inputs must be regular files"));
    try {
      text.append(buffer, size_t(n));
    } catch (const std::bad_alloc&) {
      throw Error(cat("standard input: out of memory after ", text.size(), " bytes"));
    }
  }
}

}  // namespace

int open_regular_file(const std::string& path, uint64_t& size) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY);
  if (fd < 0) throw Error(cat(path, ": cannot open: ", std::strerror(errno)));
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    const int e = errno;
    ::close(fd);
    throw Error(cat(path, ": cannot open: ", std::strerror(e)));
  }
  if (!S_ISREG(st.st_mode)) {
    ::close(fd);
    throw Error(cat(path, ": cannot read: not a regular file (", kind_of(st.st_mode), ")"));
  }
  // Reads of a regular file never block; clear the flag so the descriptor behaves as usual.
  ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) & ~O_NONBLOCK);
  size = uint64_t(st.st_size);
  return fd;
}

std::string read_file(const std::string& path, bool allow_stdin) {
  if (allow_stdin && path == "-") return read_standard_input();
  uint64_t size = 0;
  const int fd = open_regular_file(path, size);
  std::string text;
  try {
    text.resize(size_t(size));
  } catch (const std::bad_alloc&) {
    ::close(fd);
    throw Error(cat(path, ": cannot read: out of memory for its ", size, " bytes"));
  } catch (const std::length_error&) {
    ::close(fd);
    throw Error(cat(path, ": cannot read: ", size, " bytes do not fit in memory"));
  }
  bool whole = false;
  try {
    whole = read_fully(fd, text.data(), text.size(), path);
  } catch (...) {
    ::close(fd);
    throw;
  }
  ::close(fd);
  if (!whole) throw Error(cat(path, ": cannot read: the file shrank while it was read"));
  return text;
}

InputFile::InputFile(const std::string& path) : path_(path) {
  if (path == "-") {
    memory_ = read_file(path, /*allow_stdin=*/true);
    f_ = ::fmemopen(memory_.data(), memory_.size(), "rb");
    if (!f_) throw Error(cat("standard input: cannot read: ", std::strerror(errno)));
    size_ = memory_.size();
    return;
  }
  const int fd = open_regular_file(path, size_);
  f_ = ::fdopen(fd, "rb");
  if (!f_) {
    const int e = errno;
    ::close(fd);
    throw Error(cat(path, ": cannot open: ", std::strerror(e)));
  }
}

InputFile::~InputFile() {
  if (f_) std::fclose(f_);
}

void InputFile::fail_read(uint64_t offset) const {
  if (std::ferror(f_)) throw Error(cat(path_, ": read error at byte ", offset, ": ", std::strerror(errno)));
  throw Error(cat(path_, ": truncated at byte ", offset, " (the file shrank while it was read)"));
}

MappedFile::MappedFile(const std::string& path) {
  uint64_t size = 0;
  const int fd = open_regular_file(path, size);
  if (size > 0) {
    void* p = ::mmap(nullptr, size_t(size), PROT_READ, MAP_PRIVATE | MAP_POPULATE, fd, 0);
    if (p == MAP_FAILED) {
      const int e = errno;
      ::close(fd);
      throw Error(cat(path, ": cannot map its ", size, " bytes into memory: ", std::strerror(e)));
    }
    data_ = static_cast<const char*>(p);
    size_ = size_t(size);
  }
  ::close(fd);
}

MappedFile::~MappedFile() {
  if (data_) ::munmap(const_cast<char*>(data_), size_);
}

}  // namespace rp
