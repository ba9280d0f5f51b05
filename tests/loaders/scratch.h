#pragma once
// A scratch folder shared by the loader tests of this binary: files written there by name,
// the whole folder removed when the tests end.

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace rp::test {

/// The folder, made on first use for this process.
inline const std::filesystem::path& scratch() {
  static const std::filesystem::path dir = [] {
    std::filesystem::path d =
        std::filesystem::temp_directory_path() / ("raypack_loaders_test_" + std::to_string(::getpid()));
    std::filesystem::remove_all(d);
    std::filesystem::create_directories(d);
    return d;
  }();
  return dir;
}

class ScratchCleanup : public testing::Environment {
 public:
  void TearDown() override { std::filesystem::remove_all(scratch()); }
};
inline testing::Environment* const kScratchCleanup = testing::AddGlobalTestEnvironment(new ScratchCleanup);

/// Writes `bytes` verbatim (no newline translation) to scratch()/name, creating folders, and
/// returns the path.
inline std::string write_file(const std::string& name, const std::string& bytes) {
  const std::filesystem::path path = scratch() / name;
  std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), std::streamsize(bytes.size()));
  return path.string();
}

}  // namespace rp::test
