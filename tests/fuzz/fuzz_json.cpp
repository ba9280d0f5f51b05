/// libFuzzer target: rp::load_json_scene (nlohmann-json's parser, then every key, range and
/// shape check of io/loaders/json_scene.cpp, and the mesh path with its transforms).
///
/// Beside the input (input.json) the scratch folder holds three fixed files a scene can name
/// as a mesh: "cube.obj" (with "cube.mtl", two materials) and "cube.ply", so that
/// {"type": "mesh", "file": "cube.obj", ...} loads. Seeds: corpus/fuzz_json/, dictionary:
/// json.dict.

#include <cstddef>
#include <cstdint>
#include <string>

#include "io/loaders/load.h"
#include "tests/fuzz/fuzz_file.h"

namespace {

constexpr const char* kCubeObj =
    "mtllib cube.mtl\n"
    "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n"
    "vn 0 0 -1\nvn 0 0 1\n"
    "usemtl red\nf 1//1 4//1 3//1 2//1\nf 5//2 6//2 7//2 8//2\n"
    "usemtl blue\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
constexpr const char* kCubeMtl = "newmtl red\nKd 0.8 0.1 0.1\nKs 0.5 0.5 0.5\nNs 40\nillum 3\nnewmtl blue\nKd 0.1 0.1 0.8\n";
constexpr const char* kCubePly =
    "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 6\nproperty list uchar int vertex_indices\nend_header\n"
    "-1 -1 -1\n1 -1 -1\n1 1 -1\n-1 1 -1\n-1 -1 1\n1 -1 1\n1 1 1\n-1 1 1\n"
    "4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 1 2 6 5\n4 2 3 7 6\n4 3 0 4 7\n";

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const bool meshes_written = [] {
    rp::fuzz::write_scratch("cube.obj", kCubeObj);
    rp::fuzz::write_scratch("cube.mtl", kCubeMtl);
    rp::fuzz::write_scratch("cube.ply", kCubePly);
    return true;
  }();
  (void)meshes_written;
  return rp::fuzz::run_on_file(data, size, ".json", [](const std::string& path) {
    rp::Scene scene;
    rp::load_json_scene(path, scene);
    rp::fuzz::touch(scene);
  });
}
