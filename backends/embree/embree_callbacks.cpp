#include "backends/embree/embree_callbacks.h"

#include <algorithm>
#include <limits>

namespace rp::embree::detail {

namespace {

inline const Ray& caller_ray(const RTCIntersectContext* ctx, RTCRayN* rays, unsigned n, unsigned i) {
  return reinterpret_cast<const QueryContext*>(ctx)->rays[RTCRayN_id(rays, n, i)];
}

/// The caller's ray of lane i, its far end cut at Embree's current tfar (the closest hit so far).
inline Ray query_ray(const RTCIntersectContext* ctx, RTCRayN* rays, unsigned n, unsigned i) {
  Ray r = caller_ray(ctx, rays, n, i);
  r.tfar = std::min(r.tfar, RTCRayN_tfar(rays, n, i));
  return r;
}

/// The instance whose child scene Embree is in (instID[0] of the context), or kNoInstance.
inline uint32_t current_instance(const TriangleData& d, const RTCIntersectContext* ctx) {
  return d.first_instance_geom == kNoInstance ? kNoInstance : ctx->instID[0] - d.first_instance_geom;
}

/// The caller's ray i as the triangle test sees it: the world ray, or its object-space image
/// (rp::object_ray, the simd backend's bits) in an instance's child scene; false when that
/// image is outside the valid-ray rule, where no instance is traced (README, Hit convention).
inline bool test_ray(const TriangleData& d, const RTCIntersectContext* ctx, RTCRayN* rays, unsigned n, unsigned i,
                     Ray& out) {
  const Ray& r = caller_ray(ctx, rays, n, i);
  const uint32_t inst = current_instance(d, ctx);
  if (inst == kNoInstance) {
    out = r;
    return true;
  }
  out = object_ray(r, d.scene->instances()[inst].world_to_object);
  return valid_ray(out);
}

}  // namespace

template <typename Kind>
void user_bounds(const RTCBoundsFunctionArguments* a) {
  const Scene& s = *static_cast<const UserData*>(a->geometryUserPtr)->scene;
  const Box3f b = s.prim_bounds(Kind::base(s) + a->primID);
  *a->bounds_o = {b.lo.x, b.lo.y, b.lo.z, 0.0f, b.hi.x, b.hi.y, b.hi.z, 0.0f};
}

template <typename Kind>
void user_intersect(const RTCIntersectFunctionNArguments* a) {
  const Scene& s = *static_cast<const UserData*>(a->geometryUserPtr)->scene;
  RTCRayN* rays = RTCRayHitN_RayN(a->rayhit, a->N);
  RTCHitN* hits = RTCRayHitN_HitN(a->rayhit, a->N);
  for (unsigned i = 0; i < a->N; ++i) {
    if (a->valid[i] == 0) continue;
    const Intersection<float> h = s.intersect_analytic(Kind::base(s) + a->primID, query_ray(a->context, rays, a->N, i));
    if (!h.hit) continue;
    RTCRayN_tfar(rays, a->N, i) = h.t;
    RTCHitN_u(hits, a->N, i) = h.u;
    RTCHitN_v(hits, a->N, i) = h.v;
    RTCHitN_Ng_x(hits, a->N, i) = 0.0f;
    RTCHitN_Ng_y(hits, a->N, i) = 0.0f;
    RTCHitN_Ng_z(hits, a->N, i) = 0.0f;
    RTCHitN_primID(hits, a->N, i) = a->primID;
    RTCHitN_geomID(hits, a->N, i) = a->geomID;
    RTCHitN_instID(hits, a->N, i, 0) = a->context->instID[0];
  }
}

template <typename Kind>
void user_occluded(const RTCOccludedFunctionNArguments* a) {
  const Scene& s = *static_cast<const UserData*>(a->geometryUserPtr)->scene;
  for (unsigned i = 0; i < a->N; ++i) {
    if (a->valid[i] == 0) continue;
    if (s.intersect_analytic(Kind::base(s) + a->primID, caller_ray(a->context, a->ray, a->N, i)).hit)
      RTCRayN_tfar(a->ray, a->N, i) = -std::numeric_limits<float>::infinity();
  }
}

template void user_bounds<SphereKind>(const RTCBoundsFunctionArguments*);
template void user_bounds<QuadricKind>(const RTCBoundsFunctionArguments*);
template void user_bounds<PolygonKind>(const RTCBoundsFunctionArguments*);
template void user_intersect<SphereKind>(const RTCIntersectFunctionNArguments*);
template void user_intersect<QuadricKind>(const RTCIntersectFunctionNArguments*);
template void user_intersect<PolygonKind>(const RTCIntersectFunctionNArguments*);
template void user_occluded<SphereKind>(const RTCOccludedFunctionNArguments*);
template void user_occluded<QuadricKind>(const RTCOccludedFunctionNArguments*);
template void user_occluded<PolygonKind>(const RTCOccludedFunctionNArguments*);

void occlusion_band_filter(const RTCFilterFunctionNArguments* a) {
  const TriangleData& d = *static_cast<const TriangleData*>(a->geometryUserPtr);
  for (unsigned i = 0; i < a->N; ++i) {
    if (a->valid[i] == 0) continue;
    Ray r;
    if (!test_ray(d, a->context, a->ray, a->N, i, r) ||
        (in_band(r, RTCRayN_tfar(a->ray, a->N, i)) &&
         !scalar_triangle(*d.scene, d.prim_base + RTCHitN_primID(a->hit, a->N, i), r).hit))
      a->valid[i] = 0;
  }
}

/// Intersection filter on an instanced mesh's triangle geometry: a candidate counts only for a
/// ray whose object-space image is valid (test_ray); EmbreeBackend::settle decides the band.
void instance_valid_filter(const RTCFilterFunctionNArguments* a) {
  const TriangleData& d = *static_cast<const TriangleData*>(a->geometryUserPtr);
  for (unsigned i = 0; i < a->N; ++i) {
    Ray r;
    if (a->valid[i] != 0 && !test_ray(d, a->context, a->ray, a->N, i, r)) a->valid[i] = 0;
  }
}

}  // namespace rp::embree::detail
