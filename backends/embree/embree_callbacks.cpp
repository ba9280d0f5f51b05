#include "backends/embree/embree_callbacks.h"

#include <algorithm>
#include <limits>

#include "core/geometry/closest_point.h"

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
  Gated* gated = reinterpret_cast<const QueryContext*>(a->context)->gated;
  for (unsigned i = 0; i < a->N; ++i) {
    if (a->valid[i] == 0) continue;
    Intersection<float> h;
    if (gated) {  // the first crossing that the query takes, over the caller's whole interval
      const Ray& r = caller_ray(a->context, rays, a->N, i);
      for_each_analytic_hit(s, Kind::base(s) + a->primID, r, kNoInstance, [&](const Hit& c) {
        if (!gated->offer(r, c)) return false;
        h = {true, c.t, c.u, c.v};
        return true;
      });
    } else {
      h = s.intersect_analytic(Kind::base(s) + a->primID, query_ray(a->context, rays, a->N, i));
    }
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
  Gated* gated = reinterpret_cast<const QueryContext*>(a->context)->gated;
  for (unsigned i = 0; i < a->N; ++i) {
    if (a->valid[i] == 0) continue;
    const Ray& r = caller_ray(a->context, a->ray, a->N, i);
    const bool hit = gated ? for_each_analytic_hit(s, Kind::base(s) + a->primID, r, kNoInstance,
                                                   [&](const Hit& c) { return gated->offer(r, c); })
                           : s.intersect_analytic(Kind::base(s) + a->primID, r).hit;
    if (hit) RTCRayN_tfar(a->ray, a->N, i) = -std::numeric_limits<float>::infinity();
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

void gated_filter(const RTCFilterFunctionNArguments* a) {
  Gated& g = *reinterpret_cast<const QueryContext*>(a->context)->gated;
  const Scene& s = *g.numbering.scene;
  for (unsigned i = 0; i < a->N; ++i) {
    if (a->valid[i] == 0) continue;
    a->valid[i] = 0;
    const Ray& r = caller_ray(a->context, a->ray, a->N, i);
    const uint32_t inst = g.numbering.instance(RTCHitN_instID(a->hit, a->N, i, 0));
    const uint32_t prim = g.numbering.prim_id(RTCHitN_geomID(a->hit, a->N, i), RTCHitN_primID(a->hit, a->N, i), inst);
    const Ray tested = inst == kNoInstance ? r : object_ray(r, s.instances()[inst].world_to_object);
    if (!valid_ray(tested)) continue;
    const Intersection<float> h = scalar_triangle(s, prim, tested);
    if (h.hit && g.offer(r, Hit{h.t, prim, h.u, h.v, inst})) a->valid[i] = -1;
  }
}

bool point_callback(RTCPointQueryFunctionArguments* a) {
  PointContext& c = *static_cast<PointContext*>(a->userPtr);
  const Scene& s = *c.numbering.scene;
  const uint32_t inst =
      c.instance != kNoInstance
          ? c.instance
          : c.numbering.instance(a->context->instStackSize > 0 ? a->context->instID[0] : RTC_INVALID_GEOMETRY_ID);
  const uint32_t prim = c.numbering.prim_id(a->geomID, a->primID, inst);
  const PrimLocation at = s.locate(prim);
  const float before = c.search.best.distance;
  if (at.kind == PrimKind::triangle) {
    const MeshView& m = s.meshes()[at.shape];
    const Vec3f v0 = m.vertex(at.local, 0), v1 = m.vertex(at.local, 1), v2 = m.vertex(at.local, 2);
    if (zero_area(v0, v1, v2)) return false;
    const SurfacePointT<float> p = closest_on_placed_triangle(
        c.search.point, v0, v1, v2, inst == kNoInstance ? nullptr : &s.instances()[inst].object_to_world);
    c.search.take({p.p, length(p.p - c.search.point), prim, inst, p.u, p.v});
  } else {
    c.search.take(s.closest_on_analytic(prim, c.search.point));
  }
  if (!(c.search.best.distance < before)) return false;
  a->query->radius = c.search.best.distance * c.radius_scale;
  return true;
}

}  // namespace rp::embree::detail
