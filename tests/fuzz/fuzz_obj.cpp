/// libFuzzer target: rp::load_obj (tinyobjloader's OBJ and MTL parsers, then raypack's
/// triangulation, de-indexing, material mapping and checks).
///
/// The input is written twice, as input.obj and as input.mtl, and load_obj reads input.obj:
/// an input that says "mtllib input.mtl" has its own bytes parsed as its material library too
/// (each parser skips the other's statements), so one file drives both parsers. Seeds:
/// corpus/fuzz_obj/, dictionary: obj.dict.

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

#include "io/loaders/load.h"
#include "tests/fuzz/fuzz_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  rp::fuzz::write_scratch("input.mtl", std::span(data, size));
  return rp::fuzz::run_on_file(data, size, ".obj", [](const std::string& path) {
    rp::Scene scene;
    rp::load_obj(path, scene);
    rp::fuzz::touch(scene);
  });
}
