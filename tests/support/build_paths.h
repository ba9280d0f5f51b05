#pragma once
// Where this build's source tree, the real models and the programs the tests run lie. CMake
// sets them when it configures, on build_paths.cpp alone (tests/CMakeLists.txt): no other test
// file's compile line names a path of this tree, so a clone in another folder compiles every
// other test file to the same object and reuses it from the compiler cache (docs/testing.md).

namespace rp::test {

/// The repository's root (PROJECT_SOURCE_DIR), absolute.
extern const char* const kSourceDir;
/// The folder of the real models (RAYPACK_SHARED_SCENES); tests that read it skip, saying so,
/// when it is absent.
extern const char* const kSharedScenes;
/// The raypack command of this build, absolute.
extern const char* const kRaypackExe;
/// Open MPI's mpirun as CMake found it; empty in a build without MPI.
extern const char* const kMpiexec;

}  // namespace rp::test
