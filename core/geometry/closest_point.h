#pragma once
/// Closest points on primitives to a query point, in T (float for the backends, double for
/// the reference): the routines of every closest-point query (core/queries.h).

#include <algorithm>
#include <cstddef>
#include <limits>
#include <span>

#include "base/math.h"
#include "core/affine.h"
#include "core/geometry/polygon.h"

namespace rp {

/// A point on a primitive and its parameters: for a triangle Embree's barycentrics,
/// p = (1-u-v) v0 + u v1 + v v2; for other primitives as their routine documents.
template <typename T>
struct SurfacePointT {
  Vec3<T> p;
  T u = 0, v = 0;
};

/// |a - b|^2.
template <typename T>
T distance_squared(const Vec3<T>& a, const Vec3<T>& b) {
  const Vec3<T> d = a - b;
  return dot(d, d);
}

/// The point of segment [a, b] closest to p, and its parameter s in [0, 1] (p = a + s (b - a)).
template <typename T>
SurfacePointT<T> closest_on_segment(const Vec3<T>& p, const Vec3<T>& a, const Vec3<T>& b) {
  const Vec3<T> ab = b - a;
  const T len2 = dot(ab, ab);
  const T s = len2 > T(0) ? std::clamp(dot(p - a, ab) / len2, T(0), T(1)) : T(0);
  return {a + ab * s, s, T(0)};
}

/// The point of triangle (a, b, c) closest to p, by the Voronoi regions of its vertices, edges
/// and face (Ericson, "Real-Time Collision Detection", 2005, section 5.1.5), with Embree's
/// barycentrics (u on b, v on c). A zero-area triangle gives the closest point of its edges.
template <typename T>
SurfacePointT<T> closest_on_triangle(const Vec3<T>& p, const Vec3<T>& a, const Vec3<T>& b, const Vec3<T>& c) {
  const Vec3<T> ab = b - a, ac = c - a, ap = p - a;
  const T d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= T(0) && d2 <= T(0)) return {a, T(0), T(0)};
  const Vec3<T> bp = p - b;
  const T d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= T(0) && d4 <= d3) return {b, T(1), T(0)};
  const T vc = d1 * d4 - d3 * d2;
  if (vc <= T(0) && d1 >= T(0) && d3 <= T(0)) {
    const T s = d1 / (d1 - d3);
    return {a + ab * s, s, T(0)};
  }
  const Vec3<T> cp = p - c;
  const T d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= T(0) && d5 <= d6) return {c, T(0), T(1)};
  const T vb = d5 * d2 - d1 * d6;
  if (vb <= T(0) && d2 >= T(0) && d6 <= T(0)) {
    const T s = d2 / (d2 - d6);
    return {a + ac * s, T(0), s};
  }
  const T va = d3 * d6 - d5 * d4;
  if (va <= T(0) && (d4 - d3) >= T(0) && (d5 - d6) >= T(0)) {
    const T s = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {b + (c - b) * s, T(1) - s, s};
  }
  const T sum = va + vb + vc;
  if (!(sum > T(0))) {  // zero area (or NaN): the closest point of the three edges
    SurfacePointT<T> best = closest_on_segment(p, a, b);
    best = {best.p, best.u, T(0)};
    T d = distance_squared(best.p, p);
    const SurfacePointT<T> e2 = closest_on_segment(p, a, c), e3 = closest_on_segment(p, b, c);
    if (const T d2e = distance_squared(e2.p, p); d2e < d) best = {e2.p, T(0), e2.u}, d = d2e;
    if (distance_squared(e3.p, p) < d) best = {e3.p, T(1) - e3.u, e3.u};
    return best;
  }
  const T v = vb / sum, w = vc / sum;
  return {a + ab * v + ac * w, v, w};
}

/// True when triangle (a, b, c) has zero area in float (its edges' cross product is 0): no
/// surface, so no hit and no closest point (as the trees leave it out).
inline bool zero_area(const Vec3f& a, const Vec3f& b, const Vec3f& c) {
  const Vec3f n = cross(b - a, c - a);
  return n.x == 0.0f && n.y == 0.0f && n.z == 0.0f;
}

/// The point closest to world point p of triangle (a, b, c), given in its mesh's space and
/// placed by `object_to_world` (null: a world mesh): its corners mapped into the world in
/// float, then closest_on_triangle there. Every backend computes a triangle's point this way.
inline SurfacePointT<float> closest_on_placed_triangle(const Vec3f& p, const Vec3f& a, const Vec3f& b, const Vec3f& c,
                                                       const Affine3f* object_to_world) {
  if (!object_to_world) return closest_on_triangle(p, a, b, c);
  return closest_on_triangle(p, object_to_world->point(a), object_to_world->point(b), object_to_world->point(c));
}

/// The point of the plane n . P + d = 0 (n not zero) closest to p.
template <typename T>
Vec3<T> closest_on_plane(const Vec3<T>& p, const Vec3<T>& n, T d) {
  return p - n * ((dot(n, p) + d) / dot(n, n));
}

/// The point of the planar polygon `verts` (its plane `plane`) closest to p: p's projection
/// onto the plane when it falls inside the polygon (the even-odd rule of
/// intersect_polygon_even_odd, which is also the convex test's answer inside a convex
/// polygon), else the closest point of its edges.
template <typename T>
Vec3<T> closest_on_polygon(const Vec3<T>& p, PolygonVerts<T> verts, const PolygonPlane<T>& plane) {
  const size_t count = verts.size();
  const Vec3<T> q = closest_on_plane(p, plane.n, plane.d);
  const ProjectionAxes pa = projection_axes(plane.drop_axis);
  bool inside = false;
  for (size_t i = 0, j = count - 1; i < count; j = i++) {
    const T xi = verts[i][pa.x], yi = verts[i][pa.y], xj = verts[j][pa.x], yj = verts[j][pa.y];
    if ((yi > q[pa.y]) != (yj > q[pa.y]) && q[pa.x] < (xj - xi) * (q[pa.y] - yi) / (yj - yi) + xi) inside = !inside;
  }
  if (inside) return q;
  Vec3<T> best = verts[0];
  T d = std::numeric_limits<T>::infinity();
  for (size_t i = 0, j = count - 1; i < count; j = i++) {
    const Vec3<T> e = closest_on_segment(p, verts[j], verts[i]).p;
    if (const T de = distance_squared(e, p); de < d) best = e, d = de;
  }
  return best;
}

}  // namespace rp
