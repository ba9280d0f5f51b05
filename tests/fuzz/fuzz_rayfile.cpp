/// libFuzzer target: rp::read_rays and rp::read_hits, binary and CSV (io/rayfile.h).
///
/// Byte 0 of the input chooses the reader and the format, the rest is the file:
///   bit 0: 0 = binary (input.bin), 1 = CSV (input.csv)
///   bit 1: 0 = rays (read_rays),   1 = hits (read_hits)
/// so the seeds begin with the printable '0' (binary rays), '1' (CSV rays), '2' (binary hits)
/// or '3' (CSV hits). An empty input selects nothing and returns. Seeds: corpus/fuzz_rayfile/,
/// dictionary: rayfile.dict.
///
/// The rays a file yields are then traced (the first 64, both coherence hints, closest and any
/// hit) through every available backend variant and the double-precision reference over the
/// embedded default scene: a ray value that reaches an engine's assert (Embree aborts on
/// coordinates from 1.844e18 up) or a sanitizer report is a finding like a reader's crash.
/// The backends are built once, in LLVMFuzzerInitialize, before libFuzzer times any input:
/// under the sanitizers their builds take seconds, which would otherwise count to the first
/// input that yields rays (reported as a slow unit, or a timeout, where none is).

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "analysis/reference.h"
#include "backends/registry.h"
#include "io/rayfile.h"
#include "tests/fuzz/fuzz_file.h"

namespace {

/// The embedded default scene with every available backend variant and the reference built
/// over it, once.
struct Tracers {
  rp::Scene scene = rp::make_default_scene();
  std::vector<std::unique_ptr<rp::Backend>> backends;
  rp::Reference reference{scene};
  Tracers() {
    for (const rp::BackendEntry& e : rp::list_backends())
      if (e.available)
        for (const std::string& v : e.variants)
          backends.push_back(rp::make_backend(
              e.name, scene, {.variant = v, .device_config = {}, .coherent_method = {}, .incoherent_method = {}}));
  }
};

const Tracers& tracers() {
  static const Tracers t;
  return t;
}

/// The first 64 of `rays` through every backend variant and the reference (see the top).
void trace_everywhere(std::span<const rp::Ray> rays) {
  const Tracers& t = tracers();
  rays = rays.first(std::min<size_t>(rays.size(), 64));
  std::vector<rp::Hit> hits(rays.size());
  std::vector<uint8_t> occluded(rays.size());
  size_t ids = 0;  // uses every answer, so no trace is optimised away
  for (const auto& b : t.backends)
    for (rp::Coherence c : {rp::Coherence::coherent, rp::Coherence::incoherent}) {
      b->intersect(rays, hits, c);
      b->occluded(rays, occluded, c);
      for (size_t i = 0; i < rays.size(); ++i) ids += hits[i].prim_id + occluded[i];
    }
  std::vector<rp::ReferenceHit> reference_hits(rays.size());
  t.reference.intersect(rays, reference_hits);
  for (const rp::ReferenceHit& h : reference_hits) ids += h.prim_id;
  rp::fuzz::sink_count = ids;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  (void)tracers();
  return 0;
}

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
      trace_everywhere(rays);
    }
  });
}
