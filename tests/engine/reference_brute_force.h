#pragma once
// Brute force over every primitive with the double reference's documented rules
// (analysis/reference.h): what Reference::intersect, all_hits and closest_point must return,
// found without its trees. The same core/geometry routines on the same double data, so the
// reference must equal these bit for bit; only the order of the visits differs, and every rule
// is independent of it.

#include <algorithm>
#include <cstdint>
#include <span>
#include <tuple>
#include <vector>

#include "analysis/reference.h"
#include "core/geometry/closest_point.h"
#include "core/geometry/intersection.h"
#include "core/geometry/plane.h"
#include "core/geometry/polygon.h"
#include "core/geometry/quadric.h"
#include "core/geometry/sphere.h"
#include "core/geometry/triangle.h"
#include "core/queries.h"
#include "core/scene.h"

namespace rp::test {

/// The vertices of polygon i of s, converted to double.
inline std::vector<Vec3d> polygon_d(const Scene& s, uint32_t i) {
  const PolygonShape& p = s.polygons()[i];
  std::vector<Vec3d> verts;
  for (uint32_t k = 0; k < p.count; ++k) verts.push_back(Vec3d(s.polygon_vertices()[p.first + k]));
  return verts;
}

/// Every hit of `ray`: every primitive tested against the whole [tnear, tfar] by its double
/// routine, every root of it (for_each_root), an instance's triangles against the ray taken
/// into its object space by the double inverse of its transform where its float image is
/// valid, phantoms dropped (Reference::plausible); sorted by (t, prim_id, instance_id).
inline std::vector<ReferenceHit> brute_force_hits(const Scene& s, const Reference& ref, const Ray& ray) {
  std::vector<ReferenceHit> out;
  if (!valid_ray(ray)) return out;
  const Rayd r{Vec3d(ray.org), double(ray.tnear), Vec3d(ray.dir), double(ray.tfar)};
  const auto each = [&](const Rayd& rr, uint32_t id, uint32_t inst, const auto& test) {
    for_each_root(rr, test, [&](const Intersection<double>& h) {
      if (ref.plausible(ray, id, h.t, inst)) out.push_back({h.t, id, h.u, h.v, inst});
      return false;
    });
  };
  for (size_t m = 0; m < s.meshes().size(); ++m) {
    const MeshView& mesh = s.meshes()[m];
    const auto triangles = [&](const Rayd& rr, uint32_t inst) {
      for (uint32_t t = 0; t < mesh.triangle_count(); ++t) {
        const Vec3d a(mesh.vertex(t, 0)), b(mesh.vertex(t, 1)), c(mesh.vertex(t, 2));
        each(rr, s.mesh_base(m) + t, inst, [&](const Rayd& x) { return intersect_triangle_watertight(x, a, b, c); });
      }
    };
    if (!s.is_instanced(m)) triangles(r, kNoInstance);
    for (uint32_t i = 0; i < s.instances().size(); ++i) {
      const Instance& in = s.instances()[i];
      if (in.mesh == m && valid_ray(object_ray(ray, in.world_to_object)))
        triangles(object_ray(r, *inverse(Affine3d(in.object_to_world))), i);
    }
  }
  for (uint32_t i = 0; i < s.spheres().size(); ++i) {
    const Vec3d c(s.spheres()[i].center);
    const double radius = s.spheres()[i].radius;
    each(r, s.sphere_base() + i, kNoInstance, [&](const Rayd& x) { return intersect_sphere_algebraic(x, c, radius); });
  }
  for (uint32_t i = 0; i < s.quadrics().size(); ++i) {
    const Quadric<double> q = quadric_cast<double>(s.quadrics()[i].quadric);
    each(r, s.quadric_base() + i, kNoInstance, [&](const Rayd& x) { return intersect_quadric(x, q); });
  }
  for (uint32_t i = 0; i < s.polygons().size(); ++i) {
    const std::vector<Vec3d> verts = polygon_d(s, i);
    const PolygonPlane<double> plane = polygon_plane<double>(verts);
    const bool convex = s.polygons()[i].convex;
    each(r, s.polygon_base() + i, kNoInstance,
         [&](const Rayd& x) { return intersect_polygon<double>(x, verts, plane, convex); });
  }
  for (uint32_t i = 0; i < s.planes().size(); ++i) {
    const Vec3d n(s.planes()[i].normal);
    const double d = s.planes()[i].d;
    each(r, s.plane_base() + i, kNoInstance, [&](const Rayd& x) { return intersect_plane(x, n, d); });
  }
  std::sort(out.begin(), out.end(), [](const ReferenceHit& a, const ReferenceHit& b) {
    return std::tie(a.t, a.prim_id, a.instance_id) < std::tie(b.t, b.prim_id, b.instance_id);
  });
  return out;
}

/// The closest hit: the plausible hit of smallest t, at equal t the larger (prim_id,
/// instance_id), i.e. the last of brute_force_hits at the smallest t.
inline ReferenceHit brute_force(const Scene& s, const Reference& ref, const Ray& ray) {
  const std::vector<ReferenceHit> all = brute_force_hits(s, ref, ray);
  if (all.empty()) return {};
  size_t k = 0;
  while (k + 1 < all.size() && all[k + 1].t == all[0].t) ++k;
  return all[k];
}

/// The closest point of every triangle (world, or an instance's with its corners mapped into
/// the world by the double of its float transform; zero-area ones skipped), sphere, polygon
/// and plane to q.point, by the double routines; within the radius; at equal distance the
/// lowest (prim_id, instance_id). Nothing for an invalid query.
inline ReferencePoint brute_force_point(const Scene& s, const PointQuery& q) {
  ReferencePoint best;
  if (!valid_point_query(q)) return best;
  const Vec3d p(q.point);
  const auto take = [&](const Vec3d& point, uint32_t id, uint32_t inst, double u, double v) {
    const double d = length(point - p);
    if (d <= double(q.radius) && std::tie(d, id, inst) < std::tie(best.distance, best.prim_id, best.instance_id))
      best = {point, d, id, inst, u, v};
  };
  for (size_t m = 0; m < s.meshes().size(); ++m) {
    const MeshView& mesh = s.meshes()[m];
    const auto triangles = [&](const Affine3d* place, uint32_t inst) {
      for (uint32_t t = 0; t < mesh.triangle_count(); ++t) {
        if (zero_area(mesh.vertex(t, 0), mesh.vertex(t, 1), mesh.vertex(t, 2))) continue;
        Vec3d v[3];
        for (int k = 0; k < 3; ++k) v[k] = place ? place->point(Vec3d(mesh.vertex(t, k))) : Vec3d(mesh.vertex(t, k));
        const SurfacePointT<double> c = closest_on_triangle(p, v[0], v[1], v[2]);
        take(c.p, s.mesh_base(m) + t, inst, c.u, c.v);
      }
    };
    if (!s.is_instanced(m)) triangles(nullptr, kNoInstance);
    for (uint32_t i = 0; i < s.instances().size(); ++i)
      if (s.instances()[i].mesh == m) {
        const Affine3d place(s.instances()[i].object_to_world);
        triangles(&place, i);
      }
  }
  for (uint32_t i = 0; i < s.spheres().size(); ++i) {
    const Vec3d c(s.spheres()[i].center), d = p - c;
    const double radius = s.spheres()[i].radius, len = length(d);
    const Vec3d point = len > 0 ? c + d * (radius / len) : c + Vec3d(radius, 0, 0);
    const Vec2<double> uv = sphere_uv(c, radius, point);
    take(point, s.sphere_base() + i, kNoInstance, uv.x, uv.y);
  }
  for (uint32_t i = 0; i < s.polygons().size(); ++i) {
    const std::vector<Vec3d> verts = polygon_d(s, i);
    take(closest_on_polygon<double>(p, verts, polygon_plane<double>(verts)), s.polygon_base() + i, kNoInstance, 0, 0);
  }
  for (uint32_t i = 0; i < s.planes().size(); ++i)
    take(closest_on_plane(p, Vec3d(s.planes()[i].normal), double(s.planes()[i].d)), s.plane_base() + i, kNoInstance, 0,
         0);
  return best;
}

}  // namespace rp::test
