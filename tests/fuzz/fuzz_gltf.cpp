/// libFuzzer target: rp::load_gltf (tinygltf 2.7's JSON and GLB parsers, then every check of
/// io/loaders/gltf.cpp: accessors against their buffers, indices, the node hierarchy,
/// cameras, lights, materials, animations, external buffers by raypack's input rule), and
/// the animation it returns applied before, inside and after its keyframes.
///
/// The input is written as input.glb when it starts with "glTF", else as input.gltf. Beside it
/// the scratch folder holds "valid-external.bin", the buffer the seed valid-external.gltf
/// names (tests/support/gltf_files.h builds both), and a directory "folder.bin" for the seed
/// that names one. Seeds: corpus/fuzz_gltf/ (written by make_gltf_corpus.cpp), dictionary:
/// gltf.dict.

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>

#include "io/loaders/load.h"
#include "tests/fuzz/fuzz_file.h"
#include "tests/support/gltf_files.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const bool ready = [] {
    const auto file = rp::test::hierarchy_gltf();  // kept: its buffer is read below
    const std::vector<unsigned char>& bin = file.model.buffers[0].data;
    rp::fuzz::write_scratch("valid-external.bin", std::span<const uint8_t>(bin.data(), bin.size()));
    std::error_code ec;
    std::filesystem::create_directory(rp::fuzz::scratch_dir() / "folder.bin", ec);
    return true;
  }();
  (void)ready;
  const bool glb = size >= 4 && std::memcmp(data, "glTF", 4) == 0;
  return rp::fuzz::run_on_file(data, size, glb ? ".glb" : ".gltf", [](const std::string& path) {
    rp::Scene scene;
    const rp::SceneAnimation animation = rp::load_gltf(path, scene);
    for (const double t : {-1.0, 0.5 * animation.duration(), animation.duration() + 1.0}) animation.apply(scene, t);
    rp::fuzz::touch(scene);
  });
}
