#pragma once
// Brute-force double-precision closest hit over every primitive of a Scene: the independent
// answer the conformance suite holds each backend to. Triangles use the watertight test in
// double, analytic primitives the double instantiation of core/geometry.

#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "core/backend.h"
#include "core/geometry/plane.h"
#include "core/geometry/polygon.h"
#include "core/geometry/quadric.h"
#include "core/geometry/sphere.h"
#include "core/geometry/triangle.h"
#include "core/scene.h"

namespace rp::test {

struct OracleHit {
  double t = std::numeric_limits<double>::infinity();
  uint32_t prim_id = kInvalidId;
  double u = 0, v = 0;
  uint32_t instance_id = kNoInstance;
  bool hit() const { return prim_id != kInvalidId; }
};

inline Vec3d to_d(const Vec3f& v) { return Vec3d(v); }

inline Quadric<double> to_d(const Quadric<float>& q) { return quadric_cast<double>(q); }

/// Closest hit of `ray` (converted exactly to double) in [tnear, tfar]; invalid rays miss.
/// An instance's triangles are tested against the ray taken into its object space in double
/// (the double inverse of its float transform), for rays whose float object-space image
/// (rp::object_ray) is valid, the rule every backend follows. Primitives are scanned in
/// ascending (prim_id, instance_id), the last hit at an equal t winning.
inline OracleHit oracle_intersect(const Scene& s, const Ray& ray) {
  OracleHit best;
  if (!valid_ray(ray)) return best;
  Rayd r{to_d(ray.org), double(ray.tnear), to_d(ray.dir), double(ray.tfar)};
  auto take = [&](const Intersection<double>& h, uint32_t id, uint32_t instance = kNoInstance) {
    if (h.hit && h.t <= r.tfar) {
      best = {h.t, id, h.u, h.v, instance};
      r.tfar = h.t;
    }
  };
  for (size_t m = 0; m < s.meshes().size(); ++m) {
    const MeshView& mesh = s.meshes()[m];
    if (s.is_instanced(m)) {
      std::vector<std::pair<uint32_t, Affine3d>> placed;  // the instances of mesh m that trace this ray
      for (uint32_t i = 0; i < s.instances().size(); ++i) {
        const Instance& in = s.instances()[i];
        if (in.mesh == m && valid_ray(object_ray(ray, in.world_to_object)))
          placed.emplace_back(i, *inverse(Affine3d(in.object_to_world)));
      }
      for (uint32_t t = 0; t < mesh.triangle_count(); ++t)
        for (const auto& [i, w] : placed) {
          Rayd o = object_ray(r, w);
          take(intersect_triangle_watertight(o, to_d(mesh.vertex(t, 0)), to_d(mesh.vertex(t, 1)),
                                             to_d(mesh.vertex(t, 2))),
               s.mesh_base(m) + t, i);
        }
      continue;
    }
    for (uint32_t t = 0; t < mesh.triangle_count(); ++t)
      take(intersect_triangle_watertight(r, to_d(mesh.vertex(t, 0)), to_d(mesh.vertex(t, 1)), to_d(mesh.vertex(t, 2))),
           s.mesh_base(m) + t);
  }
  for (uint32_t i = 0; i < s.spheres().size(); ++i)
    take(intersect_sphere_algebraic(r, to_d(s.spheres()[i].center), double(s.spheres()[i].radius)), s.sphere_base() + i);
  for (uint32_t i = 0; i < s.quadrics().size(); ++i)
    take(intersect_quadric(r, to_d(s.quadrics()[i].quadric)), s.quadric_base() + i);
  for (uint32_t i = 0; i < s.polygons().size(); ++i) {
    const PolygonShape& p = s.polygons()[i];
    std::vector<Vec3d> verts;
    for (uint32_t k = 0; k < p.count; ++k) verts.push_back(to_d(s.polygon_vertices()[p.first + k]));
    take(intersect_polygon<double>(r, verts, polygon_plane<double>(verts), p.convex), s.polygon_base() + i);
  }
  for (uint32_t i = 0; i < s.planes().size(); ++i)
    take(intersect_plane(r, to_d(s.planes()[i].normal), double(s.planes()[i].d)), s.plane_base() + i);
  return best;
}

/// True when the oracle's answer for `ray` is ill-conditioned, so that float and double may
/// rightly disagree: the primitive changes under a tiny move of the origin (by `delta` along
/// each axis, both ways) or of tnear/tfar (1e-5 relative) — the ray grazes an edge, a
/// silhouette, a clip boundary or hits right at an interval end — or t moves by more than
/// 100 times a move of 1e-6 of the origin (a double root: a tangent or a cone's apex).
inline bool oracle_ambiguous(const Scene& s, const Ray& ray, float delta) {
  const OracleHit ref = oracle_intersect(s, ray);
  const auto other = [&](const OracleHit& h) { return h.prim_id != ref.prim_id || h.instance_id != ref.instance_id; };
  for (int axis = 0; axis < 3; ++axis)
    for (float sign : {-1.0f, 1.0f}) {
      Ray p = ray;
      p.org[axis] += sign * delta;
      if (other(oracle_intersect(s, p))) return true;
      if (!ref.hit()) continue;
      const float small = 1e-6f * std::max(1.0f, std::abs(ray.org[axis]));
      p = ray;
      p.org[axis] += sign * small;
      const OracleHit q = oracle_intersect(s, p);
      if (other(q) || std::abs(q.t - ref.t) > 100.0 * small * std::max(1.0, ref.t)) return true;
    }
  for (float f : {1.0f - 1e-5f, 1.0f + 1e-5f}) {  // a hit right at tnear or tfar
    Ray p = ray;
    p.tfar *= f;
    p.tnear *= (2.0f - f);
    if (other(oracle_intersect(s, p))) return true;
  }
  return false;
}

}  // namespace rp::test
