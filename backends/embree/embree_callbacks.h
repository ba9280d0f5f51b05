#pragma once
/// What Embree calls back during a query: the user geometry of the analytic primitives, and the
/// filters on triangle geometry that decide hits near the ends of a ray's interval by the scalar
/// test (see kBand). Internal to the Embree adapter (backends/embree/).

#include <embree3/rtcore.h>

#include <cstdint>

#include <vector>

#include "core/backend.h"
#include "core/geometry/triangle.h"
#include "core/queries.h"
#include "core/ray.h"
#include "core/scene.h"

namespace rp::embree::detail {

/// What the user-geometry callbacks see: the scene and the kind's first prim_id.
struct UserData {
  const Scene* scene;
};

/// The analytic kinds Embree sees as user geometry: the kind's prim_id range in the scene.
struct SphereKind {
  static uint32_t base(const Scene& s) { return s.sphere_base(); }
  static uint32_t count(const Scene& s) { return uint32_t(s.spheres().size()); }
};
struct QuadricKind {
  static uint32_t base(const Scene& s) { return s.quadric_base(); }
  static uint32_t count(const Scene& s) { return uint32_t(s.quadrics().size()); }
};
struct PolygonKind {
  static uint32_t base(const Scene& s) { return s.polygon_base(); }
  static uint32_t count(const Scene& s) { return uint32_t(s.polygons().size()); }
};

/// Embree's depth test is `absDen * tnear < T <= absDen * tfar` with rounded products, and its
/// t is T * rcp(absDen) with an approximate reciprocal: t is a float or two off, and a surface
/// exactly at either end of the interval can land on the wrong side (seen on the AVX2 kernels,
/// default and robust). Embree therefore searches a slightly wider interval, [tnear * (1 -
/// 2^-20), tfar * (1 + 2^-20)], and every triangle hit within kBand of either end of the
/// caller's interval is decided by the scalar Möller–Trumbore of core/geometry/ (the simd
/// backend's default test, closed at both ends), which also gives its t, u, v: in
/// occlusion_band_filter for any-hit queries, in EmbreeBackend::settle for closest hits. The
/// callbacks find the caller's exact ray through QueryContext and the ray's `id` (its index).
constexpr float kBand = 0x1p-20f;

/// Where the scene's primitives are in Embree's scenes: what a callback needs to name the
/// primitive of a candidate.
struct Numbering {
  const Scene* scene;
  const std::vector<uint32_t>* geom_base;  ///< the top scene's geometry -> its first prim_id
  uint32_t first_instance_geom;            ///< instance i is the top scene's geometry this + i

  /// The instance of top-scene geometry `inst_geom` (RTC_INVALID_GEOMETRY_ID: none).
  uint32_t instance(unsigned inst_geom) const {
    return inst_geom == RTC_INVALID_GEOMETRY_ID ? kNoInstance : inst_geom - first_instance_geom;
  }
  /// The prim_id of primitive `prim` of geometry `geom` (of the child scene of instance
  /// `inst`, or of the top scene).
  uint32_t prim_id(unsigned geom, unsigned prim, uint32_t inst) const {
    return prim + (inst == kNoInstance ? (*geom_base)[geom] : scene->mesh_base(scene->instances()[inst].mesh));
  }
};

/// One ray's query with options (core/queries.h) through rtcIntersect1 or rtcOccluded1: every
/// candidate is tested again by the scalar routine over the caller's interval (triangles:
/// Möller–Trumbore, the simd backend's default test, so t, u, v are its bits), then by the
/// gate; the context filter (gated_filter) and the user geometries decide by `mode`.
struct Gated {
  enum class Mode : uint8_t {
    closest,  ///< keep the closest that passes (best); accept it so Embree shortens the ray
    any,      ///< accept the first that passes: Embree stops
    every,    ///< collect every one that passes (every) and reject all: Embree goes on
  };
  Gated(Mode m, const Numbering& n, const TraceOptions& o) : mode(m), numbering(n), options(&o) {}

  Mode mode;
  Numbering numbering;
  const TraceOptions* options;
  size_t index = 0;  ///< the ray's index in the call
  Hit best;
  std::vector<Hit>* every = nullptr;

  HitGate gate(const Ray& r) const { return {*numbering.scene, *options, r, index}; }
  /// Decides candidate `h` (exact, of the caller's ray r): true when Embree should accept it.
  bool offer(const Ray& r, const Hit& h) {
    switch (mode) {
      case Mode::every:
        if (gate(r)(h)) every->push_back(h);
        return false;
      case Mode::any:
        return gate(r)(h);
      case Mode::closest:
        if (best.hit() &&
            (h.t > best.t || (h.t == best.t && (h.prim_id > best.prim_id ||
                                                (h.prim_id == best.prim_id && h.instance_id >= best.instance_id)))))
          return false;
        if (!gate(r)(h)) return false;
        best = h;
        return true;
    }
    return false;
  }
};

/// Embree's intersection context extended with the caller's rays (Embree passes the context
/// it was given to every callback; `embree` must stay the first member).
struct QueryContext {
  RTCIntersectContext embree;
  const Ray* rays;         ///< the caller's rays; an Embree ray's `id` is its index here
  Gated* gated = nullptr;  ///< a query with options (its context filter is gated_filter)
};

/// The context filter of a query with options (Gated): each triangle candidate tested again
/// by the scalar routine, then offered.
void gated_filter(const RTCFilterFunctionNArguments* a);

/// What rtcPointQuery's callback keeps: the search and where primitives are.
struct PointContext {
  Numbering numbering;
  PointSearch& search;
  /// The instance whose child scene is queried on its own (kNoInstance: the top scene, where
  /// Embree names the instance).
  uint32_t instance = kNoInstance;
  /// The query's space per world unit: the radius the callback sets is the best distance
  /// times this (1 in the world; a bound of the instance's world_to_object stretch).
  float radius_scale = 1.0f;
};

/// rtcPointQuery's callback (userPtr: a PointContext): the primitive's closest point, in the
/// world, offered to the search; the query's radius shrinks to the best distance (times
/// radius_scale).
bool point_callback(RTCPointQueryFunctionArguments* a);

/// True when t lies within kBand of an end of the caller's interval [tnear, tfar].
inline bool in_band(const Ray& r, float t) { return t <= r.tnear * (1.0f + kBand) || t >= r.tfar * (1.0f - kBand); }

/// Triangle `prim_id` against `r` by the scalar Möller–Trumbore; a miss for other kinds.
inline Intersection<float> scalar_triangle(const Scene& s, uint32_t prim_id, const Ray& r) {
  const PrimLocation ref = s.locate(prim_id);
  if (ref.kind != PrimKind::triangle) return {};
  const MeshView& m = s.meshes()[ref.shape];
  return intersect_triangle_mt_normal(r, m.vertex(ref.local, 0), m.vertex(ref.local, 1), m.vertex(ref.local, 2));
}

/// What a triangle geometry's filters need: the scene, the mesh's first prim_id, and, for an
/// instanced mesh's geometry, the top scene's geometry id of instance 0 (instances are
/// attached at consecutive ids from there; kNoInstance for a world mesh's geometry).
struct TriangleData {
  const Scene* scene;
  uint32_t prim_base;
  uint32_t first_instance_geom = kNoInstance;
};

/// Embree's bounds, intersect and occluded callbacks of the user geometry of `Kind`, whose
/// user data is a UserData (instantiated for SphereKind, QuadricKind and PolygonKind).
template <typename Kind>
void user_bounds(const RTCBoundsFunctionArguments* a);
template <typename Kind>
void user_intersect(const RTCIntersectFunctionNArguments* a);
template <typename Kind>
void user_occluded(const RTCOccludedFunctionNArguments* a);

/// Occlusion filter on triangle geometry: a candidate within kBand of an end of the caller's
/// interval counts only when the scalar test hits it too (see kBand); in an instance, only for
/// a ray whose object-space image is valid. Embree sets the ray's tfar to the candidate's
/// distance before calling a filter.
void occlusion_band_filter(const RTCFilterFunctionNArguments* a);

/// Intersection filter on an instanced mesh's triangle geometry: a candidate counts only for a
/// ray whose object-space image is valid (test_ray); EmbreeBackend::settle decides the band.
void instance_valid_filter(const RTCFilterFunctionNArguments* a);

}  // namespace rp::embree::detail
