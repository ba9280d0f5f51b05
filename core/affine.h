#pragma once
/// Affine maps of 3-space, p -> L p + t: an instance's placement (core/scene.h) and its
/// inverse, which takes a world ray into the instance's object space.
///
/// Why t survives the trip: with o' = W o and d' = W_L d (W = M^-1, W_L its linear part,
/// the direction NOT renormalised), o' + t d' = W (o + t d) for every t, so a hit found at t
/// in object space is the world ray's hit at the same t, with the same barycentrics.

#include <algorithm>
#include <cmath>
#include <optional>

#include "base/math.h"
#include "core/ray.h"

namespace rp {

/// p -> L p + t, stored as three rows (L_i0, L_i1, L_i2, t_i). 48 bytes for float. Every
/// product and sum is written out in one order, left to right, so a map applied in one place
/// gives the same bits as in any other (every raypack target is built with -ffp-contract=off).
template <typename T>
struct Affine3 {
  T m[3][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}};

  constexpr Affine3() = default;
  template <typename U>
  constexpr explicit Affine3(const Affine3<U>& o) {
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 4; ++j) m[i][j] = T(o.m[i][j]);
  }

  /// L p + t: ((L_i0 x + L_i1 y) + L_i2 z) + t_i.
  constexpr Vec3<T> point(const Vec3<T>& p) const {
    return {m[0][0] * p.x + m[0][1] * p.y + m[0][2] * p.z + m[0][3],
            m[1][0] * p.x + m[1][1] * p.y + m[1][2] * p.z + m[1][3],
            m[2][0] * p.x + m[2][1] * p.y + m[2][2] * p.z + m[2][3]};
  }
  /// L v (a direction: no translation).
  constexpr Vec3<T> vector(const Vec3<T>& v) const {
    return {m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z, m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
            m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z};
  }
  /// L^T v: for a map W = M^-1, W_L^T n is M's inverse transpose applied to a normal n.
  constexpr Vec3<T> transpose_vector(const Vec3<T>& v) const {
    return {m[0][0] * v.x + m[1][0] * v.y + m[2][0] * v.z, m[0][1] * v.x + m[1][1] * v.y + m[2][1] * v.z,
            m[0][2] * v.x + m[1][2] * v.y + m[2][2] * v.z};
  }
  constexpr T determinant() const {
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  }
  /// Largest row sum of |L| (the infinity norm of the linear part).
  T linear_norm() const {
    T n = 0;
    for (int i = 0; i < 3; ++i) n = std::max(n, std::abs(m[i][0]) + std::abs(m[i][1]) + std::abs(m[i][2]));
    return n;
  }
  /// The largest factor by which the linear part stretches a vector (its largest singular
  /// value, the spectral norm), from the largest eigenvalue of L^T L in closed form (Smith,
  /// "Eigenvalues of a symmetric 3 x 3 matrix", CACM 4(4), 1961) in double, rounded up by
  /// 2^-20: never below the true value.
  T largest_stretch() const {
    double a[3][3];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        a[i][j] =
            double(m[0][i]) * double(m[0][j]) + double(m[1][i]) * double(m[1][j]) + double(m[2][i]) * double(m[2][j]);
    const double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    const double q = (a[0][0] + a[1][1] + a[2][2]) / 3;
    const double p2 =
        (a[0][0] - q) * (a[0][0] - q) + (a[1][1] - q) * (a[1][1] - q) + (a[2][2] - q) * (a[2][2] - q) + 2 * off;
    double largest = std::max(a[0][0], std::max(a[1][1], a[2][2]));
    if (off > 0 && p2 > 0) {
      const double p = std::sqrt(p2 / 6);
      double b[3][3];
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) b[i][j] = (a[i][j] - (i == j ? q : 0)) / p;
      const double det = b[0][0] * (b[1][1] * b[2][2] - b[1][2] * b[2][1]) -
                         b[0][1] * (b[1][0] * b[2][2] - b[1][2] * b[2][0]) +
                         b[0][2] * (b[1][0] * b[2][1] - b[1][1] * b[2][0]);
      const double phi = std::acos(std::clamp(det / 2, -1.0, 1.0)) / 3;
      largest = std::max(largest, q + 2 * p * std::cos(phi));
    }
    return T(std::sqrt(largest) * (1 + 0x1p-20));
  }
  constexpr bool is_identity() const {
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 4; ++j)
        if (m[i][j] != (i == j ? T(1) : T(0))) return false;
    return true;
  }
  bool is_finite() const {
    for (const auto& row : m)
      for (T x : row)
        if (!std::isfinite(x)) return false;
    return true;
  }
  friend constexpr bool operator==(const Affine3& a, const Affine3& b) {
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 4; ++j)
        if (a.m[i][j] != b.m[i][j]) return false;
    return true;
  }
};
using Affine3f = Affine3<float>;
using Affine3d = Affine3<double>;

/// a after b: (a * b)(p) = a(b(p)), in T.
template <typename T>
constexpr Affine3<T> compose(const Affine3<T>& a, const Affine3<T>& b) {
  Affine3<T> c;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 4; ++j) c.m[i][j] = a.m[i][0] * b.m[0][j] + a.m[i][1] * b.m[1][j] + a.m[i][2] * b.m[2][j];
    c.m[i][3] += a.m[i][3];
  }
  return c;
}

/// The inverse of `a` by its adjugate, in double; nothing when `a` is singular or the result
/// is not finite.
inline std::optional<Affine3d> inverse(const Affine3d& a) {
  const double det = a.determinant();
  if (!(det != 0.0) || !std::isfinite(det)) return std::nullopt;
  const auto& m = a.m;
  Affine3d r;
  r.m[0][0] = (m[1][1] * m[2][2] - m[1][2] * m[2][1]) / det;
  r.m[0][1] = (m[0][2] * m[2][1] - m[0][1] * m[2][2]) / det;
  r.m[0][2] = (m[0][1] * m[1][2] - m[0][2] * m[1][1]) / det;
  r.m[1][0] = (m[1][2] * m[2][0] - m[1][0] * m[2][2]) / det;
  r.m[1][1] = (m[0][0] * m[2][2] - m[0][2] * m[2][0]) / det;
  r.m[1][2] = (m[0][2] * m[1][0] - m[0][0] * m[1][2]) / det;
  r.m[2][0] = (m[1][0] * m[2][1] - m[1][1] * m[2][0]) / det;
  r.m[2][1] = (m[0][1] * m[2][0] - m[0][0] * m[2][1]) / det;
  r.m[2][2] = (m[0][0] * m[1][1] - m[0][1] * m[1][0]) / det;
  for (int i = 0; i < 3; ++i) r.m[i][3] = -(r.m[i][0] * m[0][3] + r.m[i][1] * m[1][3] + r.m[i][2] * m[2][3]);
  if (!r.is_finite()) return std::nullopt;
  return r;
}

/// The inverse of a float map the way Embree 3 computes an instance's world-to-local map
/// (Instance::commit: rcp of its AffineSpace3fa, in Embree's baseline-ISA code, no fused
/// operations), every operation rounded to float in this order: with columns x, y, z of the
/// linear part and p its translation, the rows of the inverse are y×z, z×x, x×y over
/// det = (x.x c.x + x.y c.y) + x.z c.z (c = y×z, each cross component a.i b.j - a.j b.i of
/// rounded products), and its translation is -(q.x w0 + (q.y w1 + q.z w2)) per row.
/// Instance::world_to_object is this, not the correctly rounded inverse, because Embree's is
/// fixed: an instance traced by both backends must reach its mesh as the same float ray, or
/// a ray through a silhouette or a crevice, one ulp apart, finds different triangles.
/// Nothing when the determinant is zero or the result is not finite.
inline std::optional<Affine3f> float_inverse(const Affine3f& a) {
  const auto& m = a.m;
  const Vec3f x{m[0][0], m[1][0], m[2][0]}, y{m[0][1], m[1][1], m[2][1]}, z{m[0][2], m[1][2], m[2][2]};
  const auto cross = [](const Vec3f& u, const Vec3f& v) {
    return Vec3f{u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x};
  };
  const Vec3f rows[3] = {cross(y, z), cross(z, x), cross(x, y)};
  const float det = (x.x * rows[0].x + x.y * rows[0].y) + x.z * rows[0].z;
  if (!(det != 0.0f) || !std::isfinite(det)) return std::nullopt;
  Affine3f r;
  for (int i = 0; i < 3; ++i) {
    r.m[i][0] = rows[i].x / det;
    r.m[i][1] = rows[i].y / det;
    r.m[i][2] = rows[i].z / det;
  }
  for (int i = 0; i < 3; ++i) r.m[i][3] = -(m[0][3] * r.m[i][0] + (m[1][3] * r.m[i][1] + m[2][3] * r.m[i][2]));
  if (!r.is_finite()) return std::nullopt;
  return r;
}

/// The ray `r` in the object space of an instance whose world-to-object map is `w`: origin
/// w(o), direction w_L(d), not renormalised, tnear and tfar unchanged, so its hits keep the
/// world ray's t (see the top of this file). Every backend path and the reference's choice of
/// which rays to trace through an instance call this one function, so they see the same
/// object-space ray, bit for bit. In float it is Embree's own ray transform in its AVX2 and
/// AVX-512 kernels (xfmPoint, xfmVector: fused multiply-adds, z first), so the simd backend's
/// object rays are the bits Embree's instances trace.
template <typename T>
constexpr RayT<T> object_ray(const RayT<T>& r, const Affine3<T>& w) {
  return {w.point(r.org), r.tnear, w.vector(r.dir), r.tfar};
}
/// The float map's fused form (below) of an origin o and a direction d, for one lane (float:
/// std::fma) or several (an xsimd batch: its fma, found by argument-dependent lookup: the
/// renderer's 8-wide shading of instance hits), with the same bits in every lane.
template <typename T>
void object_ray_fused(const Affine3<T>& w, const Vec3<T>& o, const Vec3<T>& d, Vec3<T>& oo, Vec3<T>& od) {
  using std::fma;
  const auto& m = w.m;
  T* out_o[3] = {&oo.x, &oo.y, &oo.z};
  T* out_d[3] = {&od.x, &od.y, &od.z};
  for (int i = 0; i < 3; ++i) {
    *out_o[i] = fma(o.x, m[i][0], fma(o.y, m[i][1], fma(o.z, m[i][2], m[i][3])));
    *out_d[i] = fma(d.x, m[i][0], fma(d.y, m[i][1], d.z * m[i][2]));
  }
}
inline Ray object_ray(const Ray& r, const Affine3f& w) {
  Vec3f po, pd;
  object_ray_fused(w, r.org, r.dir, po, pd);
  return {po, r.tnear, pd, r.tfar};
}

}  // namespace rp
