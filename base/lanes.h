#pragma once
/// Arithmetic written once for one lane (float) and for eight (simd::float8): the shading of a
/// hit (render/shading.h) and the surface point of a triangle hit
/// (core/geometry/triangle_point.h) are templates on the lane type F, so the scalar renderer
/// and the 8-wide one perform the same operations in the same order, and every lane of the
/// 8-wide one has the scalar bits. What differs between the two is only how a few operations
/// are spelled: Lanes<F> holds them, for float here and for float8 in simd/lanes8.h.
///
/// A condition is Lanes<F>::Mask (bool, or one bit per lane); `&&`, `||` and `!` combine
/// masks without short-circuit for float8, so the generic code computes both sides of every
/// choice and picks with select(). Every operation used is exact in IEEE terms (+, -, *, /,
/// sqrt, comparisons) or defined bit for bit by both spellings (pow_nonneg, the ray-origin
/// offset), so both instantiations round alike.

#include <cmath>

#include "base/math.h"
#include "base/offset.h"
#include "base/pow.h"

namespace rp {

template <class F>
struct Lanes;

/// One lane: the operations as the scalar code has always written them.
template <>
struct Lanes<float> {
  using Mask = bool;
  static float select(bool c, float a, float b) { return c ? a : b; }
  static float sqrt(float x) { return std::sqrt(x); }
  static float floor(float x) { return std::floor(x); }
  static float abs(float x) { return std::abs(x); }
  static bool finite(float x) { return std::isfinite(x); }
  static float pow(float x, float y) { return pow_nonneg(x, y); }
  static Vec3f offset(const Vec3f& p, const Vec3f& n) { return offset_ray_origin(p, n); }
  static bool any(bool m) { return m; }
};

template <class F>
Vec3<F> select(typename Lanes<F>::Mask c, const Vec3<F>& a, const Vec3<F>& b) {
  return {Lanes<F>::select(c, a.x, b.x), Lanes<F>::select(c, a.y, b.y), Lanes<F>::select(c, a.z, b.z)};
}

/// rp::normalize in lanes: a / |a|, a zero vector staying zero.
template <class F>
Vec3<F> unit(const Vec3<F>& a) {
  const F l = Lanes<F>::sqrt(dot(a, a));
  return select<F>(l > F(0.0f), a / l, a);
}

/// std::max(a, b) in lanes: (a < b) ? b : a, with std::max's answer for NaN and ties.
template <class F>
F max_of(const F& a, const F& b) {
  return Lanes<F>::select(a < b, b, a);
}

/// rp::max_component in lanes: std::max(a.x, std::max(a.y, a.z)).
template <class F>
F max_component_of(const Vec3<F>& a) {
  return max_of(a.x, max_of(a.y, a.z));
}

template <class F>
typename Lanes<F>::Mask finite3(const Vec3<F>& v) {
  return Lanes<F>::finite(v.x) && Lanes<F>::finite(v.y) && Lanes<F>::finite(v.z);
}

}  // namespace rp
