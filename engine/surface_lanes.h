#pragma once
/// The parts of Scene::surface written in lanes (engine/lanes.h): the point of a triangle
/// hit, and the fix-up of a normal that rounding left without a direction. Scene::surface
/// calls them with one lane; the renderer's 8-wide shading with eight, so both give the same
/// bits.

#include "engine/lanes.h"
#include "engine/math.h"

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

/// Where rounding leaves the geometric normal without a direction (a point computed at a tiny
/// shape's centre from far away), both normals face the ray, and a non-finite position
/// becomes org + t dir.
template <class F>
void fix_degenerate_normal(PointLanes<F>& p, const Vec3<F>& org, const Vec3<F>& dir, const F& t) {
  const auto bad = !(dot(p.geometric_normal, p.geometric_normal) > F(0.5f));
  const Vec3<F> facing = -unit(dir);
  p.geometric_normal = select<F>(bad, facing, p.geometric_normal);
  p.shading_normal = select<F>(bad, facing, p.shading_normal);
  p.position = select<F>(bad && !finite3(p.position), org + dir * t, p.position);
}

}  // namespace rp
