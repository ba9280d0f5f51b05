// The input and output rules every reader and writer shares (io/input_file.h,
// io/output_file.h): what is refused, what is never replaced, what is left behind.

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <set>
#include <string>
#include <thread>

#include "base/error.h"
#include "base/text.h"
#include "io/input_file.h"
#include "io/output_file.h"
#include "tests/support/error_of.h"
#include "tests/support/temp_dir.h"

namespace rp {
namespace {

namespace fs = std::filesystem;
using test::error_of;
using test::TempDir;

std::string contents(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

struct stat stat_of(const std::string& path) {
  struct stat st {};
  EXPECT_EQ(::lstat(path.c_str(), &st), 0) << path;
  return st;
}

TEST(InputFile, ReadsRegularFilesWholeAndFollowsSymlinks) {
  TempDir tmp;
  std::ofstream(tmp / "a.txt") << "hello";
  fs::create_symlink(tmp / "a.txt", tmp / "link.txt");
  EXPECT_EQ(read_file(tmp / "a.txt"), "hello");
  EXPECT_EQ(read_file(tmp / "link.txt"), "hello");
  std::ofstream(tmp / "empty.txt").flush();
  EXPECT_EQ(read_file(tmp / "empty.txt"), "");
  const MappedFile m(tmp / "a.txt");
  EXPECT_EQ(std::string(m.data(), m.size()), "hello");
  const MappedFile e(tmp / "empty.txt");
  EXPECT_EQ(e.size(), 0u);
}

TEST(InputFile, RefusesEveryKindOfNonRegularFileWithoutBlocking) {
  TempDir tmp;
  const std::string fifo = tmp / "x.obj";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);  // no writer ever: a blocking open would hang here
  fs::create_directory(tmp / "dir.ply");
  fs::create_symlink("/dev/zero", tmp / "zero.json");
  EXPECT_EQ(error_of([&] { read_file(fifo); }), fifo + ": cannot read: not a regular file (a FIFO)");
  EXPECT_EQ(error_of([&] { MappedFile m(fifo); }), fifo + ": cannot read: not a regular file (a FIFO)");
  EXPECT_EQ(error_of([&] { read_file(tmp / "dir.ply"); }),
            tmp / "dir.ply" + ": cannot read: not a regular file (a directory)");
  EXPECT_EQ(error_of([&] { read_file(tmp / "zero.json"); }),
            tmp / "zero.json" + ": cannot read: not a regular file (a character device)");
  EXPECT_EQ(error_of([&] { read_file(tmp / "absent"); }), tmp / "absent" + ": cannot open: No such file or directory");
  // "-" is a file name unless the caller allows standard input.
  EXPECT_EQ(error_of([&] { read_file("-"); }), "-: cannot open: No such file or directory");
}

TEST(OutputFile, WritesARegularFileWholeOrNotAtAll) {
  TempDir tmp;
  const std::string path = tmp / "out.bin";
  write_file(path, "first");
  EXPECT_EQ(contents(path), "first");
  {
    OutputFile out(path);
    out.write("second, longer", 14);
    EXPECT_EQ(contents(path), "first") << "the target changes only at commit";
    EXPECT_EQ(tmp.entries().size(), 2u) << "the temporary sits beside the target";
    EXPECT_EQ(fs::path(out.temp_path()).extension(), ".bin") << "the temporary keeps the extension";
  }  // destroyed without commit: the temporary goes, the target stays
  EXPECT_EQ(contents(path), "first");
  EXPECT_EQ(tmp.entries(), (std::set<std::string>{"out.bin"}));
  write_file(path, "third");
  EXPECT_EQ(contents(path), "third");
  EXPECT_EQ(tmp.entries(), (std::set<std::string>{"out.bin"}));
}

TEST(OutputFile, KeepsTheModeOfTheFileItReplaces) {
  TempDir tmp;
  const std::string path = tmp / "script.sh";
  write_file(path, "#!/bin/sh\n");
  ASSERT_EQ(::chmod(path.c_str(), 0750), 0);
  write_file(path, "#!/bin/sh\necho\n");
  EXPECT_EQ(stat_of(path).st_mode & 07777, 0750u);
}

TEST(OutputFile, ASymlinkStaysALinkAndItsTargetGetsTheBytes) {
  TempDir tmp;
  fs::create_directory(tmp / "real");
  write_file(tmp / "real/target.csv", "old");
  fs::create_symlink(tmp / "real/target.csv", tmp / "link.csv");
  write_file(tmp / "link.csv", "new");
  EXPECT_TRUE(S_ISLNK(stat_of(tmp / "link.csv").st_mode));
  EXPECT_EQ(fs::read_symlink(tmp / "link.csv"), fs::path(tmp / "real/target.csv"));
  EXPECT_EQ(contents(tmp / "real/target.csv"), "new");
  EXPECT_EQ(tmp.entries(), (std::set<std::string>{"link.csv", "real"}));
  // A link to nothing is refused, not followed, and nothing is created.
  fs::create_symlink(tmp / "real/missing.csv", tmp / "dangling.csv");
  EXPECT_EQ(error_of([&] { write_file(tmp / "dangling.csv", "x"); }),
            tmp / "dangling.csv" + ": cannot write: it is a symbolic link to a missing file (not followed)");
  EXPECT_FALSE(fs::exists(tmp / "real/missing.csv"));
}

TEST(OutputFile, ADeviceIsWrittenIntoAndNeverReplaced) {
  const struct stat before = stat_of("/dev/null");
  ASSERT_TRUE(S_ISCHR(before.st_mode));
  write_file("/dev/null", std::string(100000, 'x'));
  const struct stat after = stat_of("/dev/null");
  EXPECT_TRUE(S_ISCHR(after.st_mode)) << "/dev/null is no longer a character device";
  EXPECT_EQ(after.st_ino, before.st_ino);
  EXPECT_EQ(after.st_rdev, before.st_rdev);
  // The private temporary of a device output is gone too.
  for (const auto& e : fs::directory_iterator(fs::temp_directory_path()))
    EXPECT_EQ(e.path().filename().string().find("raypack-" + std::to_string(::getpid()) + "-"), std::string::npos)
        << e.path();
}

TEST(OutputFile, AFifoReceivesTheBytesAndStaysAFifo) {
  TempDir tmp;
  const std::string fifo = tmp / "hits.bin";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::string received;
  std::thread reader([&] { received = contents(fifo); });
  write_file(fifo, "through the pipe");
  reader.join();
  EXPECT_EQ(received, "through the pipe");
  EXPECT_TRUE(S_ISFIFO(stat_of(fifo).st_mode));
  EXPECT_EQ(tmp.entries(), (std::set<std::string>{"hits.bin"}));
}

TEST(OutputFile, ADirectoryOrAMissingFolderIsRefusedAndNothingIsLeft) {
  TempDir tmp;
  fs::create_directory(tmp / "taken.png");
  EXPECT_EQ(error_of([&] { write_file(tmp / "taken.png", "x"); }), tmp / "taken.png" + ": cannot write: it is a directory");
  EXPECT_EQ(error_of([&] { write_file(tmp / "no/such/dir.png", "x"); }),
            tmp / "no/such/dir.png" + ": cannot write: No such file or directory");
  EXPECT_EQ(tmp.entries(), (std::set<std::string>{"taken.png"}));
}

/// Forks a child that opens an output in `dir`, writes to it, then receives `sig` before it
/// commits; returns the child's wait status.
int killed_mid_write(const std::string& dir, int sig) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    install_signal_cleanup();
    OutputFile out(dir + "/big.bin");
    const std::string block(1 << 20, 'x');
    for (int i = 0; i < 4; ++i) out.write(block.data(), block.size());
    ::raise(sig);
    ::_exit(0);  // not reached: the handler ends the process by the signal
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  return status;
}

TEST(OutputFile, AnInterruptedRunLeavesNoTemporaryBehind) {
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
    TempDir tmp;
    const int status = killed_mid_write(tmp.dir.string(), sig);
    ASSERT_TRUE(WIFSIGNALED(status)) << "signal " << sig;
    EXPECT_EQ(WTERMSIG(status), sig) << "the process ends by the signal it got";
    EXPECT_TRUE(tmp.entries().empty()) << "signal " << sig << " left " << *tmp.entries().begin();
  }
}

TEST(Text, OneLineKeepsValidUtf8AndReplacesControlsAndBadBytes) {
  EXPECT_EQ(one_line("plain ascii"), "plain ascii");
  EXPECT_EQ(one_line("caf\xc3\xa9 \xe2\x82\xac \xf0\x9f\x98\x80"), "caf\xc3\xa9 \xe2\x82\xac \xf0\x9f\x98\x80");
  EXPECT_EQ(one_line("two\nlines\r\x1b[31mred"), "two?lines??[31mred");
  EXPECT_EQ(one_line("bad \xff \xc3 \xc0\xaf \xed\xa0\x80 \xf4\x90\x80\x80 end"), "bad ? ? ?? ??? ???? end");
  EXPECT_EQ(printable(std::string(40, 'a')), std::string(32, 'a') + "...");
  EXPECT_EQ(printable("\x01z"), "?z");
}

}  // namespace
}  // namespace rp
