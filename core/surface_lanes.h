#pragma once
/// The parts of Scene::surface written in lanes (base/lanes.h): the point of a triangle
/// hit, and the fix-up of a normal that rounding left without a direction. Scene::surface
/// calls them with one lane; the renderer's 8-wide shading with eight, so both give the same
/// bits.

#include "base/lanes.h"
#include "base/math.h"
#include "core/affine.h"
#include "core/geometry/quadric.h"

namespace rp {

/// Position and normals of a hit point in lanes (SurfacePoint without the material).
template <class F>
struct PointLanes {
  Vec3<F> position;
  Vec3<F> geometric_normal;  ///< unit, as the primitive orients it
  Vec3<F> shading_normal;    ///< unit
};

/// The hit (u, v) of the triangle with corners c[0..2] and, where `has_normals`, vertex normals
/// n[0..2]: the barycentric position (1 - u - v) c0 + u c1 + v c2, the geometric normal
/// normalize((c1 - c0) x (c2 - c0)), and the interpolated vertex normal, normalised, where
/// the mesh has normals and it is not zero (else the geometric one).
template <class F>
PointLanes<F> triangle_point(const Vec3<F> c[3], const Vec3<F> n[3], typename Lanes<F>::Mask has_normals, const F& u,
                             const F& v) {
  const F w = F(1.0f) - u - v;
  PointLanes<F> p;
  p.position = c[0] * w + c[1] * u + c[2] * v;
  p.geometric_normal = unit(cross(c[1] - c[0], c[2] - c[0]));
  const Vec3<F> ni = n[0] * w + n[1] * u + n[2] * v;
  p.shading_normal = select<F>(has_normals && dot(ni, ni) > F(0.0f), unit(ni), p.geometric_normal);
  return p;
}

/// A sphere hit at t along (org, dir): the normal unit(org + dir t - centre), the point
/// centre + normal radius (on the sphere whatever the rounding of t).
template <class F>
PointLanes<F> sphere_point(const Vec3<F>& org, const Vec3<F>& dir, const F& t, const Vec3<F>& centre, const F& radius) {
  const Vec3<F> n = unit(org + dir * t - centre);
  return {centre + n * radius, n, n};
}

/// A hit at t along (org, dir) on the plane n . p + d = 0 (an unbounded plane's or a
/// polygon's): org + dir t projected onto the plane (its closest point there, which removes
/// the error of org + dir t along n), and unit(n).
template <class F>
PointLanes<F> plane_point(const Vec3<F>& org, const Vec3<F>& dir, const F& t, const Vec3<F>& n, const F& d) {
  const Vec3<F> p = org + dir * t;
  const Vec3<F> u = unit(n);
  return {p - n * ((dot(n, p) + d) / dot(n, n)), u, u};
}

/// A hit at t along (org, dir) on quadric q: org + dir t pulled back onto the surface by one
/// Newton step along the gradient (whose error grows with t), and the unit gradient there.
template <class F>
PointLanes<F> quadric_point(const Vec3<F>& org, const Vec3<F>& dir, const F& t, const Quadric<float>& q) {
  const Vec3<F> p = org + dir * t, g = q.gradient<F>(p);
  const F gg = dot(g, g);
  const Vec3<F> at = select<F>(gg > F(0.0f), p - g * (q.eval<F>(p) / gg), p);
  const Vec3<F> n = unit(q.gradient<F>(at));
  return {at, n, n};
}

/// fix_degenerate_normal's fix of the lanes `bad`, out of line: few hits need it.
template <class F>
[[gnu::noinline]] void face_the_ray(PointLanes<F>& p, const Vec3<F>& org, const Vec3<F>& dir, const F& t,
                                    typename Lanes<F>::Mask bad) {
  const Vec3<F> facing = -unit(dir);
  p.geometric_normal = select<F>(bad, facing, p.geometric_normal);
  p.shading_normal = select<F>(bad, facing, p.shading_normal);
  p.position = select<F>(bad && !finite3(p.position), org + dir * t, p.position);
}

/// Where rounding leaves the geometric normal without a direction (a point computed at a tiny
/// shape's centre from far away), both normals face the ray, and a non-finite position
/// becomes org + t dir. The test is inline (GCC had called the whole of it out of line from
/// the 8-wide shading, passing the points through memory, for a test that almost never fails).
template <class F>
[[gnu::always_inline]] inline void fix_degenerate_normal(PointLanes<F>& p, const Vec3<F>& org, const Vec3<F>& dir,
                                                         const F& t) {
  const auto bad = !(dot(p.geometric_normal, p.geometric_normal) > F(0.5f));
  if (Lanes<F>::any(bad)) face_the_ray<F>(p, org, dir, t, bad);
}

/// The world point and normals of a hit on an instance's triangle (Scene::instance_surface)
/// from `local`, its point and normals in the instance's object space (triangle_point, then
/// fix_degenerate_normal along the object-space ray): the point mapped by `object_to_world`,
/// each normal by the inverse transpose (`world_to_object`'s L^T), normalised and turned by
/// `orientation` (-1 for a mirroring map).
template <class F>
PointLanes<F> instance_point(const PointLanes<F>& local, const Affine3<F>& object_to_world,
                             const Affine3<F>& world_to_object, const F& orientation) {
  return {object_to_world.point(local.position),
          unit(world_to_object.transpose_vector(local.geometric_normal)) * orientation,
          unit(world_to_object.transpose_vector(local.shading_normal)) * orientation};
}

}  // namespace rp
