/// libFuzzer target: rp::read_rays and rp::read_hits, binary and CSV (engine/rayfile.h).
///
/// Byte 0 of the input chooses the reader and the format, the rest is the file:
///   bit 0: 0 = binary (input.bin), 1 = CSV (input.csv)
///   bit 1: 0 = rays (read_rays),   1 = hits (read_hits)
/// so the seeds begin with the printable '0' (binary rays), '1' (CSV rays), '2' (binary hits)
/// or '3' (CSV hits). An empty input selects nothing and returns. Seeds: corpus/fuzz_rayfile/,
/// dictionary: rayfile.dict.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "engine/rayfile.h"
#include "tests/fuzz/fuzz_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const bool csv = (data[0] & 1) != 0, hits = (data[0] & 2) != 0;
  return rp::fuzz::run_on_file(data + 1, size - 1, csv ? ".csv" : ".bin", [hits](const std::string& path) {
    if (hits) {
      const std::vector<rp::HitRecord> records = rp::read_hits(path);
      rp::fuzz::touch(records);
    } else {
      const std::vector<rp::Ray> rays = rp::read_rays(path);
      rp::fuzz::touch(rays);
    }
  });
}
