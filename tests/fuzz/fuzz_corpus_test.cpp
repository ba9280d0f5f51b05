/// Replays every input of corpus/<target>/ and regression/<target>/ through the five fuzz
/// targets, compiled here without libFuzzer (each target's LLVMFuzzerTestOneInput is renamed
/// <target>_one_input by CMake), in every build with every compiler. An input passes when its
/// target returns normally (an rp::Error caught inside the target is normal); a crash, another
/// exception or a sanitizer report (in a sanitizer build, .ci/sanitize.sh) fails it. A missing
/// or empty corpus folder fails too, so the test cannot pass on nothing.
///
/// Names carry expectations: an input named "valid-*" must load (no rp::Error), one named
/// "bad-*" must be refused with an rp::Error; others may do either.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "tests/fuzz/fuzz_file.h"
#include "tests/support/build_paths.h"

extern "C" int fuzz_obj_one_input(const uint8_t* data, size_t size);
extern "C" int fuzz_ply_one_input(const uint8_t* data, size_t size);
extern "C" int fuzz_json_one_input(const uint8_t* data, size_t size);
extern "C" int fuzz_rayfile_one_input(const uint8_t* data, size_t size);
extern "C" int fuzz_gltf_one_input(const uint8_t* data, size_t size);

namespace {

namespace fs = std::filesystem;

using Entry = int (*)(const uint8_t*, size_t);

std::vector<fs::path> files_in(const fs::path& dir) {
  std::vector<fs::path> files;
  for (const fs::directory_entry& e : fs::directory_iterator(dir))
    if (e.is_regular_file()) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  return files;
}

std::string read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void replay(const std::string& target, Entry entry) {
  const fs::path corpus = fs::path(rp::test::kSourceDir) / "tests" / "fuzz" / "corpus" / target;
  const fs::path regression = fs::path(rp::test::kSourceDir) / "tests" / "fuzz" / "regression" / target;
  ASSERT_TRUE(fs::is_directory(corpus)) << corpus << " is missing";
  std::vector<fs::path> files = files_in(corpus);
  ASSERT_FALSE(files.empty()) << corpus << " has no inputs";
  if (fs::is_directory(regression)) {
    const std::vector<fs::path> more = files_in(regression);
    files.insert(files.end(), more.begin(), more.end());
  }
  for (const fs::path& file : files) {
    SCOPED_TRACE(file.string());
    const std::string bytes = read_bytes(file);
    try {
      EXPECT_EQ(entry(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size()), 0);
    } catch (const std::exception& e) {
      ADD_FAILURE() << "escaped the target: " << e.what();
      continue;
    } catch (...) {
      ADD_FAILURE() << "escaped the target: an exception not derived from std::exception";
      continue;
    }
    const std::string name = file.filename().string();
    const std::string& error = rp::fuzz::last_error();
    if (name.starts_with("valid-")) {
      EXPECT_EQ(error, "") << "a valid-* input must load";
    } else if (name.starts_with("bad-")) {
      EXPECT_NE(error, "") << "a bad-* input must be refused with an rp::Error";
    }
  }
}

TEST(FuzzCorpus, Obj) { replay("fuzz_obj", fuzz_obj_one_input); }
TEST(FuzzCorpus, Ply) { replay("fuzz_ply", fuzz_ply_one_input); }
TEST(FuzzCorpus, Json) { replay("fuzz_json", fuzz_json_one_input); }
TEST(FuzzCorpus, Rayfile) { replay("fuzz_rayfile", fuzz_rayfile_one_input); }
TEST(FuzzCorpus, Gltf) { replay("fuzz_gltf", fuzz_gltf_one_input); }

}  // namespace
