#pragma once
/// pow_nonneg (base/pow.h) on 8 lanes: the same operations in the same order, in two
/// halves of 4 doubles, so that every lane has the scalar routine's bits. AVX2+FMA translation
/// units only.

#include <immintrin.h>

#include <cmath>

#include "base/pow.h"
#include "simd/float8.h"

namespace rp::simd {

namespace pow8_detail {

/// The power for 4 lanes whose x is > 0, as m (in (sqrt(1/2), sqrt(2))) and exponent e.
RP_SIMD_INLINE __m128 pow4(__m128 m, __m128i e, __m128 y) {
  using namespace rp::pow_detail;
  const __m256d md = _mm256_cvtps_pd(m), one = _mm256_set1_pd(1.0);
  const __m256d s = _mm256_div_pd(_mm256_sub_pd(md, one), _mm256_add_pd(md, one));
  const __m256d s2 = _mm256_mul_pd(s, s);
  __m256d p = _mm256_set1_pd(kLog2[8]);
  for (int k = 7; k >= 0; --k) p = _mm256_fmadd_pd(p, s2, _mm256_set1_pd(kLog2[k]));
  __m256d z = _mm256_mul_pd(_mm256_cvtps_pd(y), _mm256_fmadd_pd(s, p, _mm256_cvtepi32_pd(e)));
  z = _mm256_min_pd(_mm256_max_pd(z, _mm256_set1_pd(kMinExponent)), _mm256_set1_pd(kMaxExponent));
  const __m256d n = _mm256_round_pd(z, _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC);
  const __m256d t = _mm256_mul_pd(_mm256_sub_pd(z, n), _mm256_set1_pd(kLn2));
  __m256d q = _mm256_set1_pd(kExp[13]);
  for (int k = 12; k >= 0; --k) q = _mm256_fmadd_pd(q, t, _mm256_set1_pd(kExp[k]));
  const __m256i biased = _mm256_add_epi64(_mm256_cvtepi32_epi64(_mm256_cvtpd_epi32(n)), _mm256_set1_epi64x(1023));
  const __m256d scale = _mm256_castsi256_pd(_mm256_slli_epi64(biased, 52));
  return _mm256_cvtpd_ps(_mm256_mul_pd(q, scale));
}

}  // namespace pow8_detail

/// pow_nonneg lane by lane, with its bits: x^y for x >= 0, y >= 0 (0^0 = 1, 0^y = 0); a lane
/// outside that domain goes to std::pow, as in the scalar routine.
RP_SIMD_INLINE float8 pow8(const float8& x, const float8& y) {
  using namespace rp::pow_detail;
  const __m256 zero = _mm256_setzero_ps(), big = _mm256_set1_ps(3.0e38f);
  const __m256 in_domain = _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(x, zero, _CMP_GE_OQ), _mm256_cmp_ps(y, zero, _CMP_GE_OQ)),
                                         _mm256_and_ps(_mm256_cmp_ps(x, big, _CMP_LE_OQ), _mm256_cmp_ps(y, big, _CMP_LE_OQ)));
  // x = m 2^e, a denormal scaled up first (exactly).
  const __m256 tiny = _mm256_cmp_ps(x, _mm256_set1_ps(0x1p-126f), _CMP_LT_OQ);
  const __m256i bits = _mm256_castps_si256(_mm256_blendv_ps(x, _mm256_mul_ps(x, _mm256_set1_ps(0x1p24f)), tiny));
  __m256i e = _mm256_sub_epi32(_mm256_srli_epi32(bits, 23), _mm256_set1_epi32(127));
  e = _mm256_sub_epi32(e, _mm256_and_si256(_mm256_castps_si256(tiny), _mm256_set1_epi32(24)));
  __m256 m = _mm256_castsi256_ps(
      _mm256_or_si256(_mm256_and_si256(bits, _mm256_set1_epi32(0x007fffff)), _mm256_set1_epi32(0x3f800000)));
  const __m256 high = _mm256_cmp_ps(m, _mm256_set1_ps(kSqrt2), _CMP_GT_OQ);
  m = _mm256_blendv_ps(m, _mm256_mul_ps(m, _mm256_set1_ps(0.5f)), high);
  e = _mm256_sub_epi32(e, _mm256_castps_si256(high));  // + 1 where high (the mask is -1)
  const __m128 lo = pow8_detail::pow4(_mm256_castps256_ps128(m), _mm256_castsi256_si128(e), _mm256_castps256_ps128(y));
  const __m128 hi =
      pow8_detail::pow4(_mm256_extractf128_ps(m, 1), _mm256_extracti128_si256(e, 1), _mm256_extractf128_ps(y, 1));
  __m256 r = _mm256_set_m128(hi, lo);
  r = _mm256_blendv_ps(r, zero, _mm256_cmp_ps(x, zero, _CMP_EQ_OQ));           // 0^y = 0
  r = _mm256_blendv_ps(r, _mm256_set1_ps(1.0f), _mm256_cmp_ps(y, zero, _CMP_EQ_OQ));  // x^0 = 1
  if (_mm256_movemask_ps(in_domain) != 0xff) {  // rare: the scalar routine's std::pow
    alignas(32) float xs[8], ys[8], rs[8];
    _mm256_store_ps(xs, x);
    _mm256_store_ps(ys, y);
    _mm256_store_ps(rs, r);
    const uint32_t out = ~uint32_t(_mm256_movemask_ps(in_domain)) & 0xffu;
    for (int l = 0; l < 8; ++l)
      if (out >> l & 1u) rs[l] = std::pow(xs[l], ys[l]);
    r = _mm256_load_ps(rs);
  }
  return r;
}

}  // namespace rp::simd
