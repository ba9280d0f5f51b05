#pragma once
/// Lanes<float8>: the operations of base/lanes.h spelled for eight lanes, each giving every
/// lane the bits of the one-lane spelling (tested in tests/simd/). AVX2+FMA translation units
/// only.

#include <immintrin.h>

#include <limits>

#include "base/lanes.h"
#include "base/offset.h"
#include "simd/float8.h"
#include "simd/pow8.h"

namespace rp {

template <>
struct Lanes<simd::float8> {
  using F = simd::float8;
  using Mask = simd::mask8;
  static F select(const Mask& c, const F& a, const F& b) { return xsimd::select(c, a, b); }
  static F sqrt(const F& x) { return xsimd::sqrt(x); }
  static F floor(const F& x) { return xsimd::floor(x); }
  static F abs(const F& x) { return xsimd::abs(x); }
  /// std::isfinite: |x| <= FLT_MAX, false for NaN and +-inf.
  static Mask finite(const F& x) { return xsimd::abs(x) <= F(std::numeric_limits<float>::max()); }
  static F pow(const F& x, const F& y) { return simd::pow8(x, y); }
  /// rp::offset_ray_origin on each lane, its operations in its order.
  static Vec3<F> offset(const Vec3<F>& p, const Vec3<F>& n) {
    return {offset_axis(p.x, n.x), offset_axis(p.y, n.y), offset_axis(p.z, n.z)};
  }
  static bool any(const Mask& m) { return simd::movemask(m) != 0; }

 private:
  static F offset_axis(const F& p, const F& n) {
    using namespace offset_detail;
    const __m256i of = _mm256_cvttps_epi32(F(kIntScale) * n);  // int32_t(kIntScale * n), truncated
    const __m256i bits = _mm256_castps_si256(p);
    const __m256i neg = _mm256_castps_si256(p < F(0.0f));
    const __m256i step = _mm256_sub_epi32(_mm256_xor_si256(of, neg), neg);  // -of where p < 0
    const F moved = _mm256_castsi256_ps(_mm256_add_epi32(bits, step));
    return xsimd::select(xsimd::abs(p) < F(kOrigin), p + F(kFloatScale) * n, moved);
  }
};

}  // namespace rp
