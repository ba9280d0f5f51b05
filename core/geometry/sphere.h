#pragma once
/// Scalar reference ray/sphere tests: the numerically careful one, the lecture notes' geometric one
/// and the textbook one (kept on purpose as the inaccurate baseline for stability studies).
///
/// Every intersect_sphere_* routine takes a center c and a radius (> 0), works for origins
/// inside, on and outside the sphere and for directions of any nonzero length, accepts the
/// smallest finite root t with r.tnear <= t <= r.tfar, and returns (u, v) from sphere_uv.
/// Miss (hit == false, t == +inf, u == v == 0): no root in the interval, a zero direction,
/// or any NaN in the ray, the center or the radius.

#include <algorithm>
#include <cmath>
#include <utility>

#include "base/math.h"
#include "core/geometry/intersection.h"
#include "core/ray.h"

namespace rp {

/// Outward unit normal (p - c) / radius at a point p on the sphere (unit up to rounding).
template <typename T>
constexpr Vec3<T> sphere_normal(const Vec3<T>& c, T radius, const Vec3<T>& p) {
  return (p - c) / radius;
}

/// Spherical surface parameters of a point p on the sphere (c, radius), as Vec2 {u, v}:
/// u = phi / (2*pi) in [0, 1), phi = atan2(z, x) of (p - c), measured from +x towards +z;
/// v = theta / pi in [0, 1], theta the angle between p - c and +y (v = 0 at the +y pole).
/// Inverse: p = c + radius * (sin(theta) cos(phi), cos(theta), sin(theta) sin(phi)).
/// At the poles u = 0.
template <typename T>
Vec2<T> sphere_uv(const Vec3<T>& c, T radius, const Vec3<T>& p) {
  const Vec3<T> n = sphere_normal(c, radius, p);
  const T two_pi = T(2 * kPi);
  T phi = std::atan2(n.z, n.x);
  if (phi < T(0)) phi += two_pi;
  T u = phi / two_pi;
  if (!(u < T(1))) u = T(0);  // phi just below 2*pi can round up to 1
  const T theta = std::acos(std::clamp(n.y, T(-1), T(1)));
  return {u, theta / T(kPi)};
}

/// The hit of r with sphere (c, radius) at the accepted root t.
template <typename T>
Intersection<T> sphere_intersection(const RayT<T>& r, const Vec3<T>& c, T radius, T t) {
  const Vec2<T> uv = sphere_uv(c, radius, r.at(t));
  return make_intersection(t, uv.x, uv.y);
}

/// The smaller of the sorted roots t0 <= t1 that lies in the ray interval, as a sphere hit.
template <typename T>
Intersection<T> sphere_pick_root(const RayT<T>& r, const Vec3<T>& c, T radius, T t0, T t1) {
  if (t1 < t0) std::swap(t0, t1);
  if (in_ray_interval(r, t0)) return sphere_intersection(r, c, radius, t0);
  if (in_ray_interval(r, t1)) return sphere_intersection(r, c, radius, t1);
  return {};
}

/// Ray/sphere test with the numerically stable quadratic (the reference method).
template <typename T>
Intersection<T> intersect_sphere_algebraic(const RayT<T>& r, const Vec3<T>& c, T radius) {
  // Haines, Günther & Akenine-Möller 2019, "Precision Improvements for Ray/Sphere
  // Intersection", Ray Tracing Gems ch. 7 (the discriminant and root forms):
  // a t^2 + 2 b' t + c = 0 with f = o - c, a = d.d, b' = f.d, c = f.f - r^2;
  // b'^2 - a c = a * disc with disc = r^2 - |f - (b'/a) d|^2 (no cancellation for grazing
  // rays); q = -(b' + sign(b') sqrt(a disc)); roots c/q and q/a (no cancellation either).
  const Vec3<T> f = r.org - c;
  const T a = dot(r.dir, r.dir);
  if (!(a > T(0))) return {};
  const T b_half = dot(f, r.dir);
  const T r2 = radius * radius;
  const T c_coef = dot(f, f) - r2;
  const Vec3<T> closest = f - r.dir * (b_half / a);
  const T disc = r2 - dot(closest, closest);
  if (!(disc >= T(0))) return {};
  const T q = -(b_half + std::copysign(std::sqrt(a * disc), b_half));
  // q == 0 only when b' == 0 and disc == 0: double root at t = 0 (tangent at the origin).
  if (q == T(0)) return sphere_pick_root(r, c, radius, T(0), T(0));
  return sphere_pick_root(r, c, radius, c_coef / q, q / a);
}

/// Ray/sphere test by the lecture notes' geometric method with early rejection.
template <typename T>
Intersection<T> intersect_sphere_geometric(const RayT<T>& r, const Vec3<T>& c, T radius) {
  // Lecture notes, "Ray-Sphere Intersection: Geometric Method", steps 1-7, generalized to a
  // direction of length |d| != 1: distances along the ray are divided by a = d.d.
  const T a = dot(r.dir, r.dir);
  if (!(a > T(0))) return {};
  const Vec3<T> l = c - r.org;
  const T l2 = dot(l, l);
  const T r2 = radius * radius;

  // Step 1: origin inside, on or outside.
  const bool outside = l2 > r2;
  const bool inside = l2 < r2;

  // Step 2: closest approach t_p = (L.d)/a; L.d carries its sign.
  const T l_dot_d = dot(l, r.dir);
  const T tp = l_dot_d / a;

  // Step 3: origin outside and sphere behind it: both roots are negative. Only a valid
  // rejection when negative t are not wanted (tnear >= 0).
  if (outside && l_dot_d < T(0) && r.tnear >= T(0)) return {};

  // On the surface: the roots are exactly 0 and 2 t_p.
  if (!outside && !inside) {
    if (!(l2 == r2)) return {};  // NaN
    return sphere_pick_root(r, c, radius, T(0), T(2) * tp);
  }

  // Steps 4-5: squared distance from the center to the line; miss when it exceeds r^2.
  const T dist2 = l2 - l_dot_d * l_dot_d / a;
  if (!(dist2 <= r2)) return {};

  // Step 6: half chord in t units.
  const T half_chord = std::sqrt((r2 - dist2) / a);

  // Step 7: outside -> t_p - t' first; inside -> t_p + t' (t_p - t' < 0 <= tnear is skipped,
  // which keeps a slightly-inside origin from reporting a rounded t_- >= 0).
  const T t_minus = tp - half_chord;
  const T t_plus = tp + half_chord;
  if (!(inside && r.tnear >= T(0)) && in_ray_interval(r, t_minus)) {
    return sphere_intersection(r, c, radius, t_minus);
  }
  if (in_ray_interval(r, t_plus)) return sphere_intersection(r, c, radius, t_plus);
  return {};
}

/// Ray/sphere test with the textbook quadratic formula (-b +- sqrt(b^2 - 4ac)) / 2a.
/// Suffers cancellation for distant spheres and grazing rays; kept as the baseline.
template <typename T>
Intersection<T> intersect_sphere_naive(const RayT<T>& r, const Vec3<T>& c, T radius) {
  // Lecture notes, "Ray-Sphere Intersection: Algebraic Method", steps 1-3, without the
  // d.d = 1 assumption.
  const Vec3<T> f = r.org - c;
  const T a = dot(r.dir, r.dir);
  if (!(a > T(0))) return {};
  const T b = T(2) * dot(r.dir, f);
  const T c_coef = dot(f, f) - radius * radius;
  const T disc = b * b - T(4) * a * c_coef;
  if (!(disc >= T(0))) return {};
  const T s = std::sqrt(disc);
  return sphere_pick_root(r, c, radius, (-b - s) / (T(2) * a), (-b + s) / (T(2) * a));
}

}  // namespace rp
