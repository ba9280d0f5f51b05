#pragma once
/// Scalar reference ray/polygon tests for planar polygons given as a vertex loop.

#include <cstddef>
#include <span>
#include <type_traits>

#include "base/math.h"
#include "core/geometry/intersection.h"
#include "core/geometry/plane.h"
#include "core/ray.h"

namespace rp {

/// Vertex loop of a polygon as taken by the intersect_polygon* routines: a std::span that
/// does not take part in deducing T (T comes from the ray), so a std::vector<Vec3<T>> or an
/// array converts implicitly. polygon_plane and polygon_is_convex take a plain span (pass a
/// span or name T).
template <typename T>
using PolygonVerts = std::type_identity_t<std::span<const Vec3<T>>>;

/// Supporting plane of a planar polygon: n . P + d = 0.
/// n: Newell normal, unnormalized (length = twice the area), oriented by the vertex order
/// (counter-clockwise seen from its tip). drop_axis: index (0, 1, 2) of n's largest
/// component, the axis dropped when projecting to 2D.
template <typename T>
struct PolygonPlane {
  Vec3<T> n;
  T d;
  int drop_axis;
};

/// Plane of the polygon verts (>= 3 vertices, planar or nearly so). Fewer than 3 vertices
/// or a degenerate polygon give n == 0 (every ray then misses).
template <typename T>
PolygonPlane<T> polygon_plane(std::span<const Vec3<T>> verts) {
  // Newell's method (Sutherland, Sproull & Schumacker 1974, "A Characterization of Ten
  // Hidden-Surface Algorithms"; Tampieri, "Newell's Method for Computing the Plane Equation
  // of a Polygon", Graphics Gems III): n = sum over edges (i, j) of
  // ((y_i - y_j)(z_i + z_j), (z_i - z_j)(x_i + x_j), (x_i - x_j)(y_i + y_j)).
  // d = -n . centroid of the vertices.
  Vec3<T> n(T(0));
  Vec3<T> centroid(T(0));
  const std::size_t count = verts.size();
  if (count < 3) return {n, T(0), 2};
  for (std::size_t i = 0; i < count; ++i) {
    const Vec3<T>& p = verts[i];
    const Vec3<T>& q = verts[i + 1 == count ? 0 : i + 1];
    n.x += (p.y - q.y) * (p.z + q.z);
    n.y += (p.z - q.z) * (p.x + q.x);
    n.z += (p.x - q.x) * (p.y + q.y);
    centroid += p;
  }
  centroid = centroid / T(count);
  return {n, -dot(n, centroid), max_abs_axis(n)};
}

/// The two in-plane axes kept when dropping axis `drop_axis`, cyclically after it
/// (drop z -> (x, y), drop x -> (y, z), drop y -> (z, x)).
struct ProjectionAxes {
  int x, y;
};
constexpr ProjectionAxes projection_axes(int drop_axis) {
  return {drop_axis == 2 ? 0 : drop_axis + 1, drop_axis == 0 ? 2 : (drop_axis == 1 ? 0 : 1)};
}

/// True when the planar polygon verts (>= 3 vertices) is convex: all turns have the same
/// orientation (collinear vertices allowed) and the boundary winds around once. False for
/// fewer than 3 vertices, a degenerate (zero-area) polygon, or NaN coordinates.
template <typename T>
bool polygon_is_convex(std::span<const Vec3<T>> verts) {
  // Schorn & Fisher, "Testing the Convexity of a Polygon", Graphics Gems IV: in the dominant
  // projection, consecutive edge cross products never change sign, and each coordinate's
  // direction changes sign at most twice going around (this rejects a pentagram, whose turns
  // all agree but which winds twice).
  const std::size_t count = verts.size();
  if (count < 3) return false;
  const PolygonPlane<T> plane = polygon_plane(verts);
  if (!(dot(plane.n, plane.n) > T(0))) return false;
  const ProjectionAxes pa = projection_axes(plane.drop_axis);
  const auto edge = [&](std::size_t i) {
    const Vec3<T>& p = verts[i % count];
    const Vec3<T>& q = verts[(i + 1) % count];
    return Vec2<T>{q[pa.x] - p[pa.x], q[pa.y] - p[pa.y]};
  };
  int turn_sign = 0;
  int x_changes = 0, y_changes = 0;
  int x_sign = 0, y_sign = 0;
  int first_x_sign = 0, first_y_sign = 0;
  for (std::size_t i = 0; i < count; ++i) {
    const Vec2<T> e = edge(i);
    const Vec2<T> f = edge(i + 1);
    if (e.x != e.x || e.y != e.y) return false;
    const T turn = e.x * f.y - e.y * f.x;
    const int s = turn > T(0) ? 1 : (turn < T(0) ? -1 : 0);
    if (s != 0) {
      if (turn_sign != 0 && s != turn_sign) return false;
      turn_sign = s;
    }
    const int sx = e.x > T(0) ? 1 : (e.x < T(0) ? -1 : 0);
    const int sy = e.y > T(0) ? 1 : (e.y < T(0) ? -1 : 0);
    if (sx != 0) {
      if (first_x_sign == 0) first_x_sign = sx;
      if (x_sign != 0 && sx != x_sign) ++x_changes;
      x_sign = sx;
    }
    if (sy != 0) {
      if (first_y_sign == 0) first_y_sign = sy;
      if (y_sign != 0 && sy != y_sign) ++y_changes;
      y_sign = sy;
    }
  }
  // Close the loop: the change from the last direction back to the first.
  if (x_sign != 0 && first_x_sign != x_sign) ++x_changes;
  if (y_sign != 0 && first_y_sign != y_sign) ++y_changes;
  return turn_sign != 0 && x_changes <= 2 && y_changes <= 2;
}

/// Ray hit with a convex planar polygon (verts in order, plane from polygon_plane(verts)).
/// Inside when P is on the inner side of every edge's half-space, with the boundary
/// (edges and vertices) counting as inside; independent of the sign of plane.n.
/// u == v == 0. Miss: no plane hit in [tnear, tfar], P outside, fewer than 3 vertices, NaN.
template <typename T>
Intersection<T> intersect_polygon_convex(const RayT<T>& r, PolygonVerts<T> verts,
                                         const PolygonPlane<T>& plane) {
  // Lecture notes, "Ray - Polygon Intersection": plane hit, then the convex polygon as the
  // intersection of half-spaces: s_i = ((v_{i+1} - v_i) x (P - v_i)) . n must agree in sign
  // with n for every edge i; zero (on the boundary) agrees with either sign.
  const std::size_t count = verts.size();
  if (count < 3) return {};
  const Intersection<T> h = intersect_plane(r, plane.n, plane.d);
  if (!h.hit) return {};
  const Vec3<T> p = r.at(h.t);
  bool any_pos = false, any_neg = false;
  for (std::size_t i = 0; i < count; ++i) {
    const Vec3<T>& a = verts[i];
    const Vec3<T>& b = verts[i + 1 == count ? 0 : i + 1];
    const T s = dot(cross(b - a, p - a), plane.n);
    if (s > T(0)) any_pos = true;
    else if (s < T(0)) any_neg = true;
    else if (s != s) return {};
  }
  if (any_pos && any_neg) return {};
  return h;
}

/// Ray hit with a planar polygon of any shape (self-intersecting allowed: even-odd rule).
/// verts in order, plane from polygon_plane(verts). Boundary points are classified by the
/// half-open rule, consistently: a point on an edge or vertex shared by polygons that tile a
/// region is inside exactly one of them (for exactly representable configurations).
/// u == v == 0. Miss: no plane hit in [tnear, tfar], P outside, fewer than 3 vertices, NaN.
template <typename T>
Intersection<T> intersect_polygon_even_odd(const RayT<T>& r, PolygonVerts<T> verts,
                                           const PolygonPlane<T>& plane) {
  // Plane hit, projection onto the dominant coordinate plane (lecture notes, "Ray - Polygon
  // Intersection"), then the crossing-number test with a +x test ray (Haines, "Point in
  // Polygon Strategies", Graphics Gems IV, section 1.2; W. R. Franklin's pnpoly). An edge
  // counts when its end points are on different sides of the half-open split y > py, so a
  // test ray through a vertex counts it exactly once (or not at all for a local extremum).
  const std::size_t count = verts.size();
  if (count < 3) return {};
  const Intersection<T> h = intersect_plane(r, plane.n, plane.d);
  if (!h.hit) return {};
  const Vec3<T> p3 = r.at(h.t);
  const ProjectionAxes pa = projection_axes(plane.drop_axis);
  const T px = p3[pa.x];
  const T py = p3[pa.y];
  bool inside = false;
  for (std::size_t i = 0, j = count - 1; i < count; j = i++) {
    const T xi = verts[i][pa.x], yi = verts[i][pa.y];
    const T xj = verts[j][pa.x], yj = verts[j][pa.y];
    if (xi != xi || yi != yi) return {};
    if ((yi > py) != (yj > py)) {
      const T x_cross = (xj - xi) * (py - yi) / (yj - yi) + xi;
      if (px < x_cross) inside = !inside;
    }
  }
  if (!inside) return {};
  return h;
}

/// Dispatch: intersect_polygon_convex when `convex` (e.g. from polygon_is_convex), else
/// intersect_polygon_even_odd. Same contract as those.
template <typename T>
Intersection<T> intersect_polygon(const RayT<T>& r, PolygonVerts<T> verts,
                                  const PolygonPlane<T>& plane, bool convex) {
  return convex ? intersect_polygon_convex(r, verts, plane)
                : intersect_polygon_even_odd(r, verts, plane);
}

}  // namespace rp
