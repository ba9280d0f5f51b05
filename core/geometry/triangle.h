#pragma once
/// Scalar reference ray/triangle tests: four algorithms with one contract, so they can be
/// compared against each other and against the backends.
///
/// Every intersect_triangle_* routine:
/// - is two-sided (front and back faces hit);
/// - accepts the smallest finite t with r.tnear <= t <= r.tfar (closed), and a point on an
///   edge or vertex (barycentrics >= 0, u + v <= 1, all closed);
/// - returns Embree's barycentrics: point = (1-u-v)*v0 + u*v1 + v*v2;
/// - misses (hit == false, t == +inf, u == v == 0) when its determinant computes to exactly
///   0 (a ray parallel to the triangle's plane, a degenerate triangle), and for any NaN in
///   the ray or the vertices. There is no epsilon: a nearly parallel ray or a sliver triangle
///   is tested as given.
///
/// Floating-point contraction: the engine is compiled with -ffp-contract=off (set in CMake),
/// so a*b - c*d is evaluated as two rounded products and a rounded difference exactly as
/// written. The watertight test relies on this; `#pragma STDC FP_CONTRACT OFF` is not
/// honoured by GCC, hence the compiler flag.

#include <cmath>
#include <type_traits>
#include <utility>

#include "base/math.h"
#include "core/geometry/intersection.h"
#include "core/ray.h"

namespace rp {

/// Unnormalized geometric normal cross(v1 - v0, v2 - v0); its length is twice the area.
/// Counter-clockwise vertices seen from the tip of the normal. Zero for a degenerate triangle.
template <typename T>
constexpr Vec3<T> triangle_normal(const Vec3<T>& v0, const Vec3<T>& v1, const Vec3<T>& v2) {
  return cross(v1 - v0, v2 - v0);
}

/// Möller–Trumbore ray/triangle test, two-sided, no epsilon: only det == 0 misses.
/// See the file comment for the hit contract and the (u, v) convention.
template <typename T>
Intersection<T> intersect_triangle_mt(const RayT<T>& r, const Vec3<T>& v0, const Vec3<T>& v1,
                                      const Vec3<T>& v2) {
  // Möller & Trumbore 1997, "Fast, Minimum Storage Ray/Triangle Intersection", JGT 2(1),
  // section 2; in the lecture notes' notation [t, b1, b2] = [S2.E2, S1.S, S2.D] / (S1.E1).
  const Vec3<T> e1 = v1 - v0;
  const Vec3<T> e2 = v2 - v0;
  const Vec3<T> s1 = cross(r.dir, e2);
  const T det = dot(s1, e1);
  if (det == T(0)) return {};
  const Vec3<T> s = r.org - v0;
  // One reciprocal of det scales the barycentrics and t, as in the paper's code (one
  // division instead of three; the 8-wide kernel does the same, bit for bit).
  const T inv_det = T(1) / det;
  const T b1 = dot(s1, s) * inv_det;
  if (!(b1 >= T(0) && b1 <= T(1))) return {};
  const Vec3<T> s2 = cross(s, e1);
  const T b2 = dot(s2, r.dir) * inv_det;
  if (!(b2 >= T(0) && b1 + b2 <= T(1))) return {};
  const T t = dot(s2, e2) * inv_det;
  if (!in_ray_interval(r, t)) return {};
  return make_intersection(t, b1, b2);
}

/// Möller–Trumbore with the paper's epsilon test (Möller and Trumbore 1997, listing: EPSILON
/// 0.000001): |det| < 1e-6 counts as parallel and misses. The epsilon is absolute, so it
/// rejects every ray against triangles whose det (about |e1| |e2| |dir|) falls below it, such
/// as a model scaled to millimetres; kept as the baseline `raypack stability` measures.
template <typename T>
Intersection<T> intersect_triangle_mt_epsilon(const RayT<T>& r, const Vec3<T>& v0, const Vec3<T>& v1,
                                              const Vec3<T>& v2) {
  const Vec3<T> e2 = v2 - v0;
  const T det = dot(cross(r.dir, e2), v1 - v0);
  if (!(std::abs(det) >= T(1e-6))) return {};
  return intersect_triangle_mt(r, v0, v1, v2);
}

/// a*b - c*d style helpers with one rounding per fused step, in the order Embree's Vec3
/// helpers use them (cross: msub(a.y, b.z, a.z*b.y), ...; dot: madd(a.x, b.x, madd(a.y, b.y,
/// a.z*b.z))). std::fma rounds once, as the FMA instruction does, so the 8-wide kernel that
/// evaluates the same expressions with vfmadd/vfmsub gets the same bits.
template <typename T>
Vec3<T> cross_fma(const Vec3<T>& a, const Vec3<T>& b) {
  return {std::fma(a.y, b.z, -(a.z * b.y)), std::fma(a.z, b.x, -(a.x * b.z)), std::fma(a.x, b.y, -(a.y * b.x))};
}
template <typename T>
T dot_fma(const Vec3<T>& a, const Vec3<T>& b) {
  return std::fma(a.x, b.x, std::fma(a.y, b.y, a.z * b.z));
}

/// Möller–Trumbore in the normal-first factoring (Kensler and Shirley 2006, "Optimizing
/// Ray-Triangle Intersection via Automated Search"; the form of Embree's
/// triangle_intersector_moeller.h): with e1 = v0 - v1, e2 = v2 - v0, Ng = e2 x e1,
/// C = v0 - O and R = C x D, the unnormalised barycentrics U = R.e2, V = R.e1 and distance
/// T = Ng.C are compared against |D.Ng| before any division, each sign-flipped by the sign
/// of D.Ng. This is the simd backend's default triangle test: the edge decisions are those
/// of Embree's default intersector, so the two backends split shared edges the same way.
/// See the file comment for the hit contract and the (u, v) convention.
template <typename T>
Intersection<T> intersect_triangle_mt_normal(const RayT<T>& r, const Vec3<T>& v0, const Vec3<T>& v1,
                                             const Vec3<T>& v2) {
  const Vec3<T> e1 = v0 - v1;
  const Vec3<T> e2 = v2 - v0;
  const Vec3<T> ng = cross_fma(e2, e1);
  const Vec3<T> c = v0 - r.org;
  const Vec3<T> rr = cross_fma(c, r.dir);
  const T den = dot_fma(ng, r.dir);
  if (!(den != T(0))) return {};
  const T sign = std::signbit(den) ? T(-1) : T(1);  // multiplying by -1 is the sign-bit xor
  const T abs_den = den * sign;
  const T u = dot_fma(rr, e2) * sign;
  const T v = dot_fma(rr, e1) * sign;
  if (!(u >= T(0) && v >= T(0) && u + v <= abs_den)) return {};
  const T inv = T(1) / abs_den;
  const T t = dot_fma(ng, c) * sign * inv;
  if (!in_ray_interval(r, t)) return {};
  return make_intersection(t, u * inv, v * inv);
}

/// Determinant of the 3x3 matrix with columns c0, c1, c2, by cofactor expansion along the
/// first row.
template <typename T>
constexpr T det3_columns(const Vec3<T>& c0, const Vec3<T>& c1, const Vec3<T>& c2) {
  const T m0 = c1.y * c2.z - c2.y * c1.z;
  const T m1 = c0.y * c2.z - c2.y * c0.z;
  const T m2 = c0.y * c1.z - c1.y * c0.z;
  return c0.x * m0 - c1.x * m1 + c2.x * m2;
}

/// Ray/triangle test by Cramer's rule on [-D, E1, E2] [t, b1, b2]^T = O - P0.
/// See the file comment for the hit contract and the (u, v) convention.
template <typename T>
Intersection<T> intersect_triangle_cramer(const RayT<T>& r, const Vec3<T>& v0,
                                          const Vec3<T>& v1, const Vec3<T>& v2) {
  // Seeds, "Ray-Triangle Intersection" question 1 and "Cramer's Rule Solution": each unknown
  // is |M_i| / |M| where M_i is M with column i replaced by b = O - P0.
  const Vec3<T> neg_d = -r.dir;
  const Vec3<T> e1 = v1 - v0;
  const Vec3<T> e2 = v2 - v0;
  const Vec3<T> b = r.org - v0;
  const T det = det3_columns(neg_d, e1, e2);
  if (det == T(0)) return {};
  const T b1 = det3_columns(neg_d, b, e2) / det;
  const T b2 = det3_columns(neg_d, e1, b) / det;
  if (!(b1 >= T(0) && b2 >= T(0) && b1 + b2 <= T(1))) return {};
  const T t = det3_columns(b, e1, e2) / det;
  if (!in_ray_interval(r, t)) return {};
  return make_intersection(t, b1, b2);
}

/// Two-step ray/triangle test: ray/plane, then barycentrics of the plane point.
/// See the file comment for the hit contract and the (u, v) convention.
template <typename T>
Intersection<T> intersect_triangle_two_step(const RayT<T>& r, const Vec3<T>& v0,
                                            const Vec3<T>& v1, const Vec3<T>& v2) {
  // Seeds, "Method 1: Two-Step Ray-Triangle Intersection": plane with n = E1 x E2, then
  // beta = ((P - a) x E2) . n / (n . n), gamma = (E1 x (P - a)) . n / (n . n).
  const Vec3<T> e1 = v1 - v0;
  const Vec3<T> e2 = v2 - v0;
  const Vec3<T> n = cross(e1, e2);
  const T denom = dot(n, r.dir);
  if (denom == T(0)) return {};
  const T t = dot(n, v0 - r.org) / denom;
  if (!in_ray_interval(r, t)) return {};
  const Vec3<T> ap = r.at(t) - v0;
  const T nn = dot(n, n);
  const T beta = dot(cross(ap, e2), n) / nn;
  const T gamma = dot(cross(e1, ap), n) / nn;
  if (!(beta >= T(0) && gamma >= T(0) && beta + gamma <= T(1))) return {};
  return make_intersection(t, beta, gamma);
}

/// Watertight ray/triangle test (no false misses on shared edges and vertices), two-sided.
/// See the file comment for the hit contract and the (u, v) convention.
template <typename T>
Intersection<T> intersect_triangle_watertight(const RayT<T>& r, const Vec3<T>& v0,
                                              const Vec3<T>& v1, const Vec3<T>& v2) {
  // Woop, Benthin & Wald 2013, "Watertight Ray/Triangle Intersection", JCGT 2(1), section 3
  // and the listing in its appendix; scalar form without per-ray precomputation.

  // Per-ray setup (section 3.1): kz = dominant axis of dir, kx/ky the next two, swapped
  // when dir[kz] < 0 to preserve the winding; shear constants map dir to (0, 0, 1).
  const int kz = max_abs_axis(r.dir);
  int kx = kz + 1 == 3 ? 0 : kz + 1;
  int ky = kx + 1 == 3 ? 0 : kx + 1;
  if (r.dir[kz] < T(0)) std::swap(kx, ky);
  const T sx = r.dir[kx] / r.dir[kz];
  const T sy = r.dir[ky] / r.dir[kz];
  const T sz = T(1) / r.dir[kz];

  // Vertices relative to the ray origin, then sheared (section 3.2).
  const Vec3<T> a = v0 - r.org;
  const Vec3<T> b = v1 - r.org;
  const Vec3<T> c = v2 - r.org;
  const T ax = a[kx] - sx * a[kz];
  const T ay = a[ky] - sy * a[kz];
  const T bx = b[kx] - sx * b[kz];
  const T by = b[ky] - sy * b[kz];
  const T cx = c[kx] - sx * c[kz];
  const T cy = c[ky] - sy * c[kz];

  // 2D edge functions; U weighs v0, V weighs v1, W weighs v2 (section 3.3). Products are
  // named so each is rounded once (see the file comment on contraction).
  const T cx_by = cx * by;
  const T cy_bx = cy * bx;
  const T ax_cy = ax * cy;
  const T ay_cx = ay * cx;
  const T bx_ay = bx * ay;
  const T by_ax = by * ax;
  T u = cx_by - cy_bx;
  T v = ax_cy - ay_cx;
  T w = bx_ay - by_ax;

  // An edge function of exactly 0 may be a rounding artefact: re-evaluate all three in double,
  // where the products of two floats are exact (section 3.3, "fall back to higher precision").
  if constexpr (std::is_same_v<T, float>) {
    if (u == T(0) || v == T(0) || w == T(0)) {
      const double cx_by_d = double(cx) * double(by);
      const double cy_bx_d = double(cy) * double(bx);
      const double ax_cy_d = double(ax) * double(cy);
      const double ay_cx_d = double(ay) * double(cx);
      const double bx_ay_d = double(bx) * double(ay);
      const double by_ax_d = double(by) * double(ax);
      u = T(cx_by_d - cy_bx_d);
      v = T(ax_cy_d - ay_cx_d);
      w = T(bx_ay_d - by_ax_d);
    }
  }

  // Two-sided: reject only when the signs are mixed. NaN compares false and falls through
  // to the final t check.
  if ((u < T(0) || v < T(0) || w < T(0)) && (u > T(0) || v > T(0) || w > T(0))) return {};
  const T det = u + v + w;
  if (det == T(0)) return {};

  // Scaled hit distance, tested against [tnear, tfar] * |det| before dividing (section 3.4);
  // multiplying by -1 is exact, so the sign flip is the paper's xor of the sign bit.
  const T az = sz * a[kz];
  const T bz = sz * b[kz];
  const T cz = sz * c[kz];
  const T u_az = u * az;
  const T v_bz = v * bz;
  const T w_cz = w * cz;
  const T t_scaled = u_az + v_bz + w_cz;
  const T det_sign = det < T(0) ? T(-1) : T(1);
  const T t_signed = t_scaled * det_sign;
  const T abs_det = det * det_sign;
  if (!(t_signed >= r.tnear * abs_det && t_signed <= r.tfar * abs_det)) return {};

  // Normalize; the scaled test above may pass a t one ulp outside the interval, so the
  // interval is checked again on the final value.
  const T t = t_scaled / det;
  if (!in_ray_interval(r, t)) return {};
  return make_intersection(t, v / det, w / det);
}

}  // namespace rp
