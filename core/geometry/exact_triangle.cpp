#include "core/geometry/exact_triangle.h"

#include <gmpxx.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace rp {
namespace {

/// x times 2^149, an integer for every finite float (its last bit is worth at least 2^-149),
/// as GMP's integer: exact (the product of a float and 2^149 is a double, integral, below 2^278).
mpz_class scaled(float x) { return mpz_class(std::ldexp(double(x), 149)); }

/// The sign of ((p - o) x (q - o)) . d in integers: every coordinate scaled by 2^149, which
/// multiplies the determinant by 2^(4 * 149) and keeps its sign.
int exact_side(const Vec3f& p, const Vec3f& q, const Vec3f& o, const Vec3f& d) {
  mpz_class a[3], b[3], e[3];
  for (int i = 0; i < 3; ++i) {
    const mpz_class oi = scaled(o[i]);
    a[i] = scaled(p[i]) - oi;
    b[i] = scaled(q[i]) - oi;
    e[i] = scaled(d[i]);
  }
  const mpz_class det =
      e[0] * (a[1] * b[2] - a[2] * b[1]) + e[1] * (a[2] * b[0] - a[0] * b[2]) + e[2] * (a[0] * b[1] - a[1] * b[0]);
  return sgn(det);
}

bool finite(const Vec3f& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

/// ((p - o) x (q - o)) . d in double from a = p - o and b = q - o as rounded, with the bound on
/// its error. Each of a, b is rounded once (relative 2^-53); each product of a term's three
/// factors and the sums are rounded, 7 roundings in all on the way to any term of the
/// permanent sum_i |d_i| (|a_j b_k| + |a_k b_j|), so the value errs by less than 8 * 2^-53 of
/// the permanent, itself computed within 6 ulps. No product of these (differences of floats,
/// or zero) underflows or overflows a double.
struct Side {
  double value, bound;
  Side(const Vec3d& a, const Vec3d& b, const Vec3d& d) {
    const double x = a.y * b.z - a.z * b.y, y = a.z * b.x - a.x * b.z, z = a.x * b.y - a.y * b.x;
    value = d.x * x + d.y * y + d.z * z;
    bound = 0x1p-50 * (std::abs(d.x) * (std::abs(a.y * b.z) + std::abs(a.z * b.y)) +
                       std::abs(d.y) * (std::abs(a.z * b.x) + std::abs(a.x * b.z)) +
                       std::abs(d.z) * (std::abs(a.x * b.y) + std::abs(a.y * b.x)));
  }
  /// The exact sign: the double value's where it is farther from 0 than the bound, 0 where
  /// every product is 0 (exactly), else in integers.
  int sign(const Vec3f& p, const Vec3f& q, const Vec3f& o, const Vec3f& d) const {
    if (value > bound) return 1;
    if (value < -bound) return -1;
    if (bound == 0.0 || !(bound < std::numeric_limits<double>::infinity())) return 0;  // (0: a NaN or infinite input)
    return exact_side(p, q, o, d);
  }
};

}  // namespace

int edge_side(const Vec3f& p, const Vec3f& q, const Vec3f& o, const Vec3f& d) {
  return Side(Vec3d(p) - Vec3d(o), Vec3d(q) - Vec3d(o), Vec3d(d)).sign(p, q, o, d);
}

Intersection<float> intersect_triangle_exact(const Ray& r, const Vec3f& v0, const Vec3f& v1, const Vec3f& v2) {
  if (!(finite(r.org) && finite(r.dir) && finite(v0) && finite(v1) && finite(v2))) return {};
  // The edge functions of (v2, v0), (v0, v1) and (v1, v2) in double (U + V + W = Ng.d in
  // exact arithmetic), their exact signs, and from the same values u and v.
  const Vec3d o(r.org), d(r.dir), c0 = Vec3d(v0) - o, c1 = Vec3d(v1) - o, c2 = Vec3d(v2) - o;
  const Side U(c2, c0, d), V(c0, c1, d), W(c1, c2, d);
  const int su = U.sign(v2, v0, r.org, r.dir), sv = V.sign(v0, v1, r.org, r.dir), sw = W.sign(v1, v2, r.org, r.dir);
  if (!inside_edges(su, sv, sw)) return {};
  // t by Möller–Trumbore's normal Ng = (v2 - v0) x (v0 - v1): Ng.(v0 - o) / Ng.d.
  const double sum = U.value + V.value + W.value;
  const Vec3d ng = cross(Vec3d(v2) - Vec3d(v0), Vec3d(v0) - Vec3d(v1));
  const double t = dot(ng, c0) / dot(ng, d);
  if (sum == 0.0 || !std::isfinite(t)) return {};  // the ray as good as in the triangle's plane
  const float tf = float(t);
  if (!in_ray_interval(r, tf)) return {};
  const double u = std::clamp(U.value / sum, 0.0, 1.0), v = std::clamp(V.value / sum, 0.0, 1.0 - u);
  return make_intersection(tf, float(u), float(v));
}

}  // namespace rp
