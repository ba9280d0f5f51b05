#pragma once
/// Writing what raypack produces (images, AOVs, hit and ray files, JSON, charts): one rule for
/// every writer, so an output is complete or absent and never replaces what it should not.
///
/// By what `path` names when the output is opened:
/// - a regular file, or nothing yet: the data goes to a temporary file beside it,
///   ".raypack-<pid>-<n>-<name>" (the name keeps the target's extension, which some writers
///   go by; the mode of a file it replaces), and commit() flushes it to the disk and renames
///   it over `path`. Readers see the old file or the whole new one, never a part.
/// - a symlink: followed, and the rule applied to what it points to (the link stays a link,
///   its target gets the new bytes); a link to nothing is refused, not followed.
/// - a character or block device, a FIFO or a socket (/dev/null, /dev/stdout on a pipe or
///   a terminal, a named pipe): never replaced. The data goes to a private temporary file in
///   the temporary folder ($TMPDIR or /tmp), and commit() copies it into the device, so a
///   run that fails writes nothing there either.
/// - a directory, or a path whose folder does not exist: rp::Error naming the path.
/// Until commit(), the destructor removes the temporary file, and so does the handler that
/// install_signal_cleanup() sets for SIGINT, SIGTERM and SIGHUP (an interrupted run leaves
/// nothing behind). A run that could not clean up (SIGKILL, a crash, a lost node) leaves its
/// temporary, which the next output of the same name in that folder removes: the maker holds
/// a lock (flock) on its temporary for as long as it lives, so a temporary of that name whose
/// lock is free and whose pid is no live process here is stale. Every failure throws
/// rp::Error "<path>: cannot write: <reason>".

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace rp {

class OutputFile {
 public:
  explicit OutputFile(const std::string& path);
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  /// The path as given.
  const std::string& path() const { return path_; }
  /// The temporary file, for writers that open a file by name (it exists, empty, until they
  /// write it; its name ends with the target's extension).
  const std::string& temp_path() const { return temp_; }
  /// The temporary file, open for reading and writing at offset 0, for writers that take a
  /// descriptor (a child process's standard output, say).
  int fd() const { return fd_; }
  /// True when path() names a device, FIFO or socket: temp_path() is then a private file in
  /// the temporary folder, copied into the device by commit(); else it lies beside the file
  /// it replaces.
  bool into_device() const { return target_.empty(); }

  /// Appends n bytes to the temporary file.
  void write(const void* data, size_t n);
  /// Makes the output appear at path() (see the top of this header); at most once.
  void commit();

  [[noreturn]] void fail(const std::string& reason) const;

 private:
  std::string path_;    ///< as given
  std::string target_;  ///< what a rename replaces (symlinks resolved); empty for a device
  std::string temp_;
  int fd_ = -1;
  int slot_ = -1;       ///< the signal-cleanup slot holding temp_
  bool committed_ = false;
};

/// Writes all `n` bytes at byte `offset` of the open file `fd` (pwrite until done, EINTR
/// retried); returns 0, or the errno of the write that failed (EIO for a write of 0 bytes).
int pwrite_all(int fd, const void* data, size_t n, uint64_t offset);

/// Writes `bytes` to `path` by the rule above.
void write_file(const std::string& path, std::string_view bytes);

/// Checks, before any work, that an OutputFile at `path` can be made now: what the constructor
/// checks, and a temporary file made in its folder and removed again. Leaves nothing behind;
/// throws the rp::Error the constructor would.
void check_output(const std::string& path);

/// A file a command reads or writes, with the flag that named it (for messages).
struct NamedFile {
  std::string flag;  ///< "--scene", "-o", ...
  std::string path;  ///< as given; "" is skipped (an output not asked for)
};

/// Refuses, before any work, an output that is the same file as an input or as another
/// output: the same path, or another name for the same file (a symbolic link, a hard link,
/// "./x" for "x"); for a file that does not exist yet, the same folder and name. Outputs that
/// are character devices (/dev/null) may repeat; "default" and "-" as inputs name no file.
/// Throws rp::Error "<flag> <path>: is the same file as <flag> <path>".
void check_distinct(const std::vector<NamedFile>& inputs, const std::vector<NamedFile>& outputs);

/// Installs handlers for SIGINT, SIGTERM and SIGHUP that remove every uncommitted temporary
/// file of every live OutputFile, then end the process by the same signal (so the exit
/// status says which). Call once, early in main().
void install_signal_cleanup();

/// A line for those handlers to print on standard error before the process ends (none by
/// default, and none after an empty one); "%s" in it stands for the signal's name (SIGTERM).
/// The handler ends it with what it found: "; unfinished outputs were removed" when it
/// removed a temporary, "; no output was left unfinished" when there was none, and a newline.
/// Rank 0 of an MPI run sets one, because mpirun ends every rank by SIGTERM when one dies.
/// Throws rp::Error beyond 511 bytes or without "%s".
void set_signal_message(std::string_view message);

}  // namespace rp
