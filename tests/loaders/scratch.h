#pragma once
// A scratch folder shared by the loader tests of this binary: files written there by name,
// the whole folder removed when the tests end; and loading such a file, or its error message.

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "core/scene.h"
#include "io/loaders/load.h"
#include "tests/support/error_of.h"

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


inline Scene obj_scene(const std::string& name, const std::string& text) {
  Scene scene;
  load_obj(write_file(name, text), scene);
  return scene;
}

inline Scene ply_scene(const std::string& name, const std::string& bytes) {
  Scene scene;
  load_ply(write_file(name, bytes), scene);
  return scene;
}

inline std::string obj_error(const std::string& name, const std::string& text) {
  const std::string path = write_file(name, text);
  return error_of([&] {
    Scene s;
    load_obj(path, s);
  });
}

inline std::string ply_error(const std::string& name, const std::string& bytes) {
  const std::string path = write_file(name, bytes);
  return error_of([&] {
    Scene s;
    load_ply(path, s);
  });
}

inline std::string path_of(const std::string& name) { return (scratch() / name).string(); }

/// The (unnormalised) normal of triangle t of m, in double.
inline Vec3d tri_cross(const TriangleMesh& m, uint32_t t) {
  const Vec3d a(m.vertex(t, 0)), b(m.vertex(t, 1)), c(m.vertex(t, 2));
  return cross(b - a, c - a);
}

}  // namespace rp::test
