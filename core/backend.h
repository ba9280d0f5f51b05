#pragma once
/// The backend seam: one abstract class, queried per batch of rays, never per ray.
///
/// A backend is built from a Scene by its constructor (see backends/registry.h) for the
/// scene's version at that moment (Scene::version). It is then safe to query from many threads
/// at once. When the scene changes (Scene::set_vertices, set_transform, add_*, remove_*),
/// update() brings the backend up to date with the least work (docs/updates.md); until then
/// intersect and occluded throw rp::Error naming the change rather than answer for the old
/// scene. Rays are const input, hits are separate output; directions are never normalized.
/// Backends return t/u/v/prim_id only; Scene::surface() derives positions and normals.
///
/// Threads: tracing is const and may run on any number of threads at once; update() and
/// every change of the scene must not overlap any trace of the backend (nor each other):
/// change the scene, update, then trace, as with Embree's rtcCommitScene.
///
/// Valid rays: rp::valid_ray (core/ray.h), the one rule every backend, the reference and the
/// renderer share. Any other ray is reported as a miss (and as not occluded) by every backend.

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "core/queries.h"
#include "core/ray.h"
#include "core/scene.h"

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

/// What one Backend::update() did.
struct UpdateReport {
  double seconds = 0;     ///< wall time of the update
  uint32_t refits = 0;    ///< trees refitted for moved vertices (boxes recomputed, topology kept)
  uint32_t rebuilds = 0;  ///< trees built anew: added geometry, a changed layout, a refit past refit_limit
  bool top = false;       ///< the instance level rebuilt (instances moved, added or removed)
};

/// Construction options; each backend documents the variants and coherent methods it accepts.
struct BackendOptions {
  std::string variant = "default";
  std::string device_config;    ///< backend-specific configuration string (embree: rtcNewDevice config)
  std::string coherent_method;  ///< how coherent spans are traced; empty: the backend's default
  std::string incoherent_method;  ///< how incoherent batches are traced; empty: the backend's default
  /// simd: update() rebuilds a tree whose SAH cost after a refit exceeds refit_limit times its
  /// cost when it was built (docs/updates.md has the figures behind the default); 1 rebuilds
  /// on any loss, +inf always refits. Embree decides for itself (its "dynamic" variant refits).
  double refit_limit = 1.25;
};

/// Whether `options` lets a hit of ray `ray` (index `index` of the call) through: its
/// geometry's mask meets the ray's, and the filter, if any, accepts it. What every backend
/// asks of each candidate hit of a query with options.
struct HitGate {
  const Scene& scene;
  const TraceOptions& options;
  const Ray& ray;
  size_t index;
  bool operator()(const Hit& h) const {
    const uint32_t g = scene.geometry_of(h.prim_id);
    return (options.mask(index) & scene.mask(g)) != 0 && (!options.filter || options.filter({ray, index, h, g}));
  }
};

class Backend {
 public:
  virtual ~Backend() = default;
  Backend(const Backend&) = delete;
  Backend& operator=(const Backend&) = delete;

  /// Closest hit of each ray: hits[i] for rays[i] (hits.size() == rays.size()); a miss is
  /// Hit{} (prim_id == kInvalidId). A hit counts only for tnear <= t <= tfar.
  /// `coherence` picks the coherent method (packets of consecutive rays) or the incoherent one
  /// (single rays, or a ray stream that the backend may reorder internally). Throws rp::Error
  /// when the scene changed since the last update() (stale()).
  /// A scene with geometry masks (Scene::set_mask) is traced as intersect with options does,
  /// every ray's mask 0xffffffff.
  void intersect(std::span<const Ray> rays, std::span<Hit> hits, Coherence coherence) const {
    if (!current()) throw_stale();
    if (scene_->has_masks()) [[unlikely]]
      return intersect(rays, hits, TraceOptions{});
    trace_closest(rays, hits, coherence);
  }

  /// Any hit: occluded[i] = 1 when rays[i] hits anything within [tnear, tfar], else 0.
  /// Throws as intersect.
  void occluded(std::span<const Ray> rays, std::span<uint8_t> occluded, Coherence coherence) const {
    if (!current()) throw_stale();
    if (scene_->has_masks()) [[unlikely]]
      return this->occluded(rays, occluded, TraceOptions{});
    trace_any(rays, occluded, coherence);
  }

  /// The closest hit of each ray among those `options` lets through (ray masks against the
  /// geometries' masks, then the filter; core/queries.h), as Embree's masks and filter
  /// functions do: a rejected candidate is as if its primitive were not there at that t.
  /// Traced ray by ray. Throws as intersect.
  void intersect(std::span<const Ray> rays, std::span<Hit> hits, const TraceOptions& options) const;
  /// Any hit that `options` lets through.
  void occluded(std::span<const Ray> rays, std::span<uint8_t> occluded, const TraceOptions& options) const;

  /// counts[i] = the number of hits of rays[i] within [tnear, tfar] that `options` lets
  /// through: each primitive it crosses, once per crossing (a sphere crossed twice counts 2),
  /// what all_hits lists. 0 for an invalid ray. Throws as intersect.
  void count_hits(std::span<const Ray> rays, std::span<uint32_t> counts, const TraceOptions& options = {}) const;
  /// Every hit of each ray within [tnear, tfar] that `options` lets through, sorted by (t,
  /// prim_id, instance_id); with max_per_ray > 0, the first max_per_ray of them. The same
  /// primitive at the same t is listed once. Throws as intersect.
  HitList all_hits(std::span<const Ray> rays, size_t max_per_ray = 0, const TraceOptions& options = {}) const;

  /// The closest point of the surface to each query point (core/queries.h): triangles (world
  /// and placed by instances), spheres, polygons and planes; among points at exactly the same
  /// distance, the lowest (prim_id, instance_id). Throws rp::Error for a scene with quadrics,
  /// which have no closest-point routine, and as intersect.
  void closest_points(std::span<const PointQuery> queries, std::span<ClosestPoint> out) const;

  /// Brings the backend up to date with its scene's changes since it was built or last
  /// updated (Embree's rtcCommitScene): moved vertices refit their trees, moved instances
  /// rebuild the instance level, added or removed geometry rebuilds what it touches. Nothing
  /// when the scene has not changed. When it throws (an Embree error, no memory), the backend
  /// stays stale and refuses to trace.
  UpdateReport update();
  /// update() under Embree's name.
  UpdateReport commit() { return update(); }

  /// True when the backend is up to date with its scene (no change since the last update).
  bool current() const noexcept { return scene_->version() == version_; }
  /// The Scene::version() the backend traces.
  uint64_t version() const noexcept { return version_; }

  virtual const BackendInfo& info() const noexcept = 0;

 protected:
  explicit Backend(const Scene& scene) : scene_(&scene), version_(scene.version()) {}
  const Scene& scene() const noexcept { return *scene_; }

  /// intersect and occluded of an up-to-date backend.
  virtual void trace_closest(std::span<const Ray> rays, std::span<Hit> hits, Coherence coherence) const noexcept = 0;
  virtual void trace_any(std::span<const Ray> rays, std::span<uint8_t> occluded,
                         Coherence coherence) const noexcept = 0;
  /// Brings the structures from version `since` to the scene's current one (update()).
  virtual UpdateReport apply_changes(uint64_t since) = 0;

  /// The queries with options (core/queries.h) of an up-to-date backend, planes excluded (the
  /// seam adds them). trace_every appends to `out` every hit of valid ray rays[index] within [tnear, tfar] that gate()
  /// lets through, in any order, a hit possibly more than once; closest_points_of answers valid queries of a scene
  /// without quadrics (found: the closest triangle, sphere or polygon point, else not found).
  virtual void trace_closest_filtered(std::span<const Ray> rays, std::span<Hit> hits,
                                      const TraceOptions& options) const = 0;
  virtual void trace_any_filtered(std::span<const Ray> rays, std::span<uint8_t> occluded,
                                  const TraceOptions& options) const = 0;
  virtual void trace_every(std::span<const Ray> rays, size_t index, const TraceOptions& options,
                           std::vector<Hit>& out) const = 0;
  virtual void closest_points_of(std::span<const PointQuery> queries, std::span<ClosestPoint> out) const = 0;

  /// The gate of ray r (index i of the call) under `options` (HitGate).
  HitGate gate(const TraceOptions& options, const Ray& r, size_t i) const { return {*scene_, options, r, i}; }

 private:
  friend class ForwardingBackend;
  [[noreturn]] void throw_stale() const;

  const Scene* scene_;
  uint64_t version_;
};

/// A backend that answers every query through another one built over the same scene (the
/// registry's scene-sharing handle, tests' wrappers); a subclass overrides what it changes.
/// The inner backend is current whenever this one is: update() goes through here.
class ForwardingBackend : public Backend {
 public:
  const BackendInfo& info() const noexcept override { return inner_->info(); }

 protected:
  ForwardingBackend(const Scene& scene, std::unique_ptr<Backend> inner) : Backend(scene), inner_(std::move(inner)) {}
  const Backend& inner() const { return *inner_; }

  void trace_closest(std::span<const Ray> rays, std::span<Hit> hits, Coherence coherence) const noexcept override {
    inner_->trace_closest(rays, hits, coherence);
  }
  void trace_any(std::span<const Ray> rays, std::span<uint8_t> occluded, Coherence coherence) const noexcept override {
    inner_->trace_any(rays, occluded, coherence);
  }
  UpdateReport apply_changes(uint64_t) override { return inner_->update(); }
  void trace_closest_filtered(std::span<const Ray> rays, std::span<Hit> hits,
                              const TraceOptions& options) const override {
    inner_->trace_closest_filtered(rays, hits, options);
  }
  void trace_any_filtered(std::span<const Ray> rays, std::span<uint8_t> occluded,
                          const TraceOptions& options) const override {
    inner_->trace_any_filtered(rays, occluded, options);
  }
  void trace_every(std::span<const Ray> rays, size_t index, const TraceOptions& options,
                   std::vector<Hit>& out) const override {
    inner_->trace_every(rays, index, options, out);
  }
  void closest_points_of(std::span<const PointQuery> queries, std::span<ClosestPoint> out) const override {
    inner_->closest_points_of(queries, out);
  }

 private:
  std::unique_ptr<Backend> inner_;
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

/// Backend::count_hits over all threads, in chunks as intersect_parallel.
void count_hits_parallel(const Backend& backend, std::span<const Ray> rays, std::span<uint32_t> counts);

/// Backend::all_hits over all threads, in chunks as intersect_parallel: every hit of each ray
/// within [tnear, tfar], the same list as one call makes.
HitList all_hits_parallel(const Backend& backend, std::span<const Ray> rays);

}  // namespace rp
