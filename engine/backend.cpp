#include "engine/backend.h"

#include <tbb/parallel_for.h>

#include <algorithm>

namespace rp {

void intersect_parallel(const Backend& backend, std::span<const Ray> rays, std::span<Hit> hits, Coherence coherence) {
  tbb::parallel_for(size_t(0), (rays.size() + kParallelChunk - 1) / kParallelChunk, [&](size_t c) {
    const size_t begin = c * kParallelChunk, n = std::min(kParallelChunk, rays.size() - begin);
    backend.intersect(rays.subspan(begin, n), hits.subspan(begin, n), coherence);
  });
}

void occluded_parallel(const Backend& backend, std::span<const Ray> rays, std::span<uint8_t> occluded,
                       Coherence coherence) {
  tbb::parallel_for(size_t(0), (rays.size() + kParallelChunk - 1) / kParallelChunk, [&](size_t c) {
    const size_t begin = c * kParallelChunk, n = std::min(kParallelChunk, rays.size() - begin);
    backend.occluded(rays.subspan(begin, n), occluded.subspan(begin, n), coherence);
  });
}

}  // namespace rp
