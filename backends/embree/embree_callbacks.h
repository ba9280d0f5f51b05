#pragma once
/// What Embree calls back during a query: the user geometry of the analytic primitives, and the
/// filters on triangle geometry that decide hits near the ends of a ray's interval by the scalar
/// test (see kBand). Internal to the Embree adapter (backends/embree/).

#include <embree3/rtcore.h>

#include <cstdint>

#include "core/geometry/triangle.h"
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

/// Embree's intersection context extended with the caller's rays (Embree passes the context
/// it was given to every callback; `embree` must stay the first member).
struct QueryContext {
  RTCIntersectContext embree;
  const Ray* rays;  ///< the caller's rays; an Embree ray's `id` is its index here
};

/// True when t lies within kBand of an end of the caller's interval [tnear, tfar].
inline bool in_band(const Ray& r, float t) { return t <= r.tnear * (1.0f + kBand) || t >= r.tfar * (1.0f - kBand); }

/// Triangle `prim_id` against `r` by the scalar Möller–Trumbore; a miss for other kinds.
inline Intersection<float> scalar_triangle(const Scene& s, uint32_t prim_id, const Ray& r) {
  const PrimLocation ref = s.locate(prim_id);
  if (ref.kind != PrimKind::triangle) return {};
  const TriangleMesh& m = s.meshes()[ref.shape];
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
