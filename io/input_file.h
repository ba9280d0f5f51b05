#pragma once
/// Opening what raypack reads (scene files, material libraries, ray and hit files, bench JSON):
/// one rule for every reader.
///
/// An input is a regular file. A directory, FIFO, character or block device or socket is
/// refused with "<path>: cannot read: not a regular file (a FIFO)" before anything is read:
/// the open itself never blocks (O_NONBLOCK, so a FIFO with no writer cannot hang it), and a
/// symlink to /dev/zero cannot feed a reader forever. Symlinks are followed. The size is
/// known before reading, and memory for it is asked for once; when that fails the message
/// names the file and the bytes. Where a command says so, the name "-" reads standard
/// input instead, up to kMaxStandardInputBytes.

#include <cstdint>
#include <cstdio>
#include <streambuf>
#include <string>

namespace rp {

/// The most bytes read from standard input ("-"), which has no size to check up front: 4 GiB.
inline constexpr uint64_t kMaxStandardInputBytes = uint64_t(4) << 30;

/// Opens `path` for reading if it is a regular file; returns the descriptor (close-on-exec,
/// blocking reads) and sets `size`. Throws rp::Error "<path>: cannot read: <reason>".
int open_regular_file(const std::string& path, uint64_t& size);

/// The whole of `path` (a regular file, or standard input for "-" when `allow_stdin`).
/// Throws rp::Error naming the path and, when memory runs out, the bytes asked for.
std::string read_file(const std::string& path, bool allow_stdin = false);

/// An input opened for reading by the rule above as a stdio stream: a regular file, or standard
/// input for "-" (read whole into memory first, up to kMaxStandardInputBytes); closed when
/// destroyed. What the record files (io/rayfile.h, io/pointfile.h) read through.
class InputFile {
 public:
  /// Throws rp::Error "<path>: cannot open: <reason>" (or cannot read) as open_regular_file.
  explicit InputFile(const std::string& path);
  ~InputFile();
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;

  std::FILE* get() const { return f_; }
  const std::string& path() const { return path_; }
  /// Bytes in the file (or read from standard input).
  uint64_t size() const { return size_; }
  /// The bytes of standard input ("-"); empty for a file.
  const std::string& memory() const { return memory_; }

  /// Throws for a stream error after a short read at byte `offset`: "<path>: read error at
  /// byte N: <reason>", or "<path>: truncated at byte N" when the file shrank.
  [[noreturn]] void fail_read(uint64_t offset) const;

 private:
  std::string path_;
  std::string memory_;
  std::FILE* f_ = nullptr;
  uint64_t size_ = 0;
};

/// A regular file mapped read-only (empty files map to no bytes). Throws rp::Error naming the
/// path, and the bytes when the mapping fails.
class MappedFile {
 public:
  explicit MappedFile(const std::string& path);
  ~MappedFile();
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;
  const char* data() const { return data_; }
  size_t size() const { return size_; }

 private:
  const char* data_ = nullptr;
  size_t size_ = 0;
};

/// A read-only std::streambuf over bytes in memory (no copy), for libraries that read a
/// std::istream (tinyobjloader).
class MemoryStreambuf : public std::streambuf {
 public:
  MemoryStreambuf(const char* data, size_t size) {
    char* p = const_cast<char*>(data);  // never written through: a get area only
    setg(p, p, p + size);
  }
};

}  // namespace rp
