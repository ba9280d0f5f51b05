/// libFuzzer target: rp::load_ply (ascii, binary little and big endian; header, size checks,
/// the fast and general binary paths, the ascii tokenizer). Seeds: corpus/fuzz_ply/,
/// dictionary: ply.dict.

#include <cstddef>
#include <cstdint>
#include <string>

#include "io/loaders/load.h"
#include "tests/fuzz/fuzz_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return rp::fuzz::run_on_file(data, size, ".ply", [](const std::string& path) {
    rp::Scene scene;
    rp::load_ply(path, scene);
    rp::fuzz::touch(scene);
  });
}
