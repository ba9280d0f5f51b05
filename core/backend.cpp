#include "core/backend.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>

#include "base/error.h"

namespace rp {

UpdateReport Backend::update() {
  if (current()) return {};
  const auto start = std::chrono::steady_clock::now();
  UpdateReport r = apply_changes(version_);
  version_ = scene_->version();
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

void Backend::throw_stale() const {
  throw Error(cat(info().name, "/", info().variant, ": the scene changed since this backend was built or updated (",
                  scene_->version() - version_, " change", scene_->version() - version_ == 1 ? "" : "s",
                  ", the last: ", scene_->last_change(), "); call update() before tracing"));
}

void for_each_chunk(size_t n, const std::function<void(size_t begin, size_t count)>& body) {
  tbb::parallel_for(size_t(0), (n + kParallelChunk - 1) / kParallelChunk, [&](size_t c) {
    const size_t begin = c * kParallelChunk;
    body(begin, std::min(kParallelChunk, n - begin));
  });
}

void intersect_parallel(const Backend& backend, std::span<const Ray> rays, std::span<Hit> hits, Coherence coherence) {
  for_each_chunk(rays.size(), [&](size_t begin, size_t n) {
    backend.intersect(rays.subspan(begin, n), hits.subspan(begin, n), coherence);
  });
}

void occluded_parallel(const Backend& backend, std::span<const Ray> rays, std::span<uint8_t> occluded,
                       Coherence coherence) {
  for_each_chunk(rays.size(), [&](size_t begin, size_t n) {
    backend.occluded(rays.subspan(begin, n), occluded.subspan(begin, n), coherence);
  });
}

}  // namespace rp
