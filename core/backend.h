#pragma once
/// The backend seam: one abstract class, queried per batch of rays, never per ray.
///
/// A backend is built from a Scene by its constructor (see backends/registry.h) and is then
/// immutable and safe to query from many threads at once. Rays are const input, hits are
/// separate output; directions are never normalized. Backends return t/u/v/prim_id only;
/// Scene::surface() derives positions and normals.
///
/// Valid rays: rp::valid_ray (core/ray.h), the one rule every backend, the reference and the
/// renderer share. Any other ray is reported as a miss (and as not occluded) by every backend.

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "core/ray.h"

namespace rp {

/// The bytes of a two-level structure by level (BackendInfo::levels).
struct LevelBytes {
  /// The top level: the world's own structure (world meshes, analytic primitives) and the one
  /// over the instances (simd: two trees; Embree: one scene holding both).
  size_t top = 0;
  /// The instanced meshes' structures, each built once however many instances place it.
  size_t meshes = 0;
};

/// What a built backend reports about itself.
struct BackendInfo {
  std::string name;      ///< registry name, e.g. "embree"
  std::string variant;   ///< e.g. "default", "robust"
  double build_seconds = 0;
  size_t bytes = 0;      ///< bytes of the acceleration structure (scene arrays excluded): levels.top + levels.meshes
  LevelBytes levels;
  std::vector<std::pair<std::string, double>> stats;  ///< backend-specific figures (nodes, depth, ...)
};

/// Construction options; each backend documents the variants and coherent methods it accepts.
struct BackendOptions {
  std::string variant = "default";
  std::string device_config;    ///< backend-specific configuration string (embree: rtcNewDevice config)
  std::string coherent_method;  ///< how coherent spans are traced; empty: the backend's default
  std::string incoherent_method;  ///< how incoherent batches are traced; empty: the backend's default
};

class Backend {
 public:
  virtual ~Backend() = default;

  /// Closest hit of each ray: hits[i] for rays[i] (hits.size() == rays.size()); a miss is
  /// Hit{} (prim_id == kInvalidId). A hit counts only for tnear <= t <= tfar.
  /// `coherence` picks the coherent method (packets of consecutive rays) or the incoherent one
  /// (single rays, or a ray stream that the backend may reorder internally).
  virtual void intersect(std::span<const Ray> rays, std::span<Hit> hits, Coherence coherence) const noexcept = 0;

  /// Any hit: occluded[i] = 1 when rays[i] hits anything within [tnear, tfar], else 0.
  virtual void occluded(std::span<const Ray> rays, std::span<uint8_t> occluded,
                        Coherence coherence) const noexcept = 0;

  virtual const BackendInfo& info() const noexcept = 0;
};

/// Rays a parallel batch hands each task: whole 8-ray packets, and enough work per task to
/// pay for the scheduling.
inline constexpr size_t kParallelChunk = 4096;

/// Calls body(begin, count) once for each chunk [begin, begin + count) of a batch of n rays:
/// consecutive chunks of kParallelChunk rays (the last one shorter), in parallel over TBB's
/// threads (the current task arena's). Every parallel trace cuts its batch this way, so the
/// same rays make the same backend calls whichever caller cuts them.
void for_each_chunk(size_t n, const std::function<void(size_t begin, size_t count)>& body);

/// Traces a batch with all threads (TBB) in chunks of kParallelChunk rays (for_each_chunk),
/// each chunk one call of backend.intersect (so a coherent span stays whole within a chunk).
void intersect_parallel(const Backend& backend, std::span<const Ray> rays, std::span<Hit> hits, Coherence coherence);

/// The same for any hits.
void occluded_parallel(const Backend& backend, std::span<const Ray> rays, std::span<uint8_t> occluded,
                       Coherence coherence);

}  // namespace rp
