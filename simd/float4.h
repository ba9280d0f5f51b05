#pragma once
/// The 4-wide vocabulary of the BVH builder: a box corner or a centroid per register (x, y, z
/// and a spare lane). Include this only from translation units compiled for AVX2+FMA (link
/// rp::avx2), as the builder's are: there these SSE4.1 operations take their VEX forms.
///
/// float4 and int4 are the compiler's vector types, not classes such as xsimd's batch: the
/// builder keeps arrays of them (its bins, 3.5 KB per node), and GCC 12 fills and joins
/// arrays of a class with other, longer code than arrays of a vector (objdump of
/// bvh8_build.cpp.o). Their arithmetic operators are the vector types' own (one SSE
/// instruction each); what the builder needs beyond them is here.

#include <immintrin.h>

#include <cstdint>

#include "simd/prefetch.h"

namespace rp::simd {

/// Four floats in one SSE register.
using float4 = __m128;
/// Four 32-bit integers in one SSE register.
using int4 = __m128i;

/// All lanes = v.
inline float4 splat4(float v) { return _mm_set1_ps(v); }
inline int4 splat4(int32_t v) { return _mm_set1_epi32(v); }
/// Lanes x, y, z, w.
inline float4 make_float4(float x, float y, float z, float w) { return _mm_setr_ps(x, y, z, w); }

/// The four floats at unaligned `p`.
inline float4 load4(const float* p) { return _mm_loadu_ps(p); }
/// The three floats at unaligned `p` and a zero fourth lane. Reads 16 bytes, so the fourth
/// float must be readable; its bits are dropped (they may not even be a float).
inline float4 load3(const float* p) {
  return _mm_and_ps(_mm_loadu_ps(p), _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0)));
}
/// Stores v at the 16-byte aligned `p`.
inline void store4(float* p, float4 v) { _mm_store_ps(p, v); }
inline void store4(int32_t* p, int4 v) { _mm_store_si128(reinterpret_cast<__m128i*>(p), v); }

/// Lane-wise minimum and maximum. For floats with the operand order of MINPS and MAXPS: when
/// either lane is NaN the result is the lane of b.
inline float4 min4(float4 a, float4 b) { return _mm_min_ps(a, b); }
inline float4 max4(float4 a, float4 b) { return _mm_max_ps(a, b); }
inline int4 min4(int4 a, int4 b) { return _mm_min_epi32(a, b); }
inline int4 max4(int4 a, int4 b) { return _mm_max_epi32(a, b); }

/// Surface area of the non-empty box [lo, hi] from its x, y, z lanes: 2 (e.x e.y + e.y e.z +
/// e.z e.x) for e = hi - lo, the operations of Box3f::area in its order (the same bits).
inline float area4(float4 lo, float4 hi) {
  const float4 e = _mm_sub_ps(hi, lo);
  const float4 p = _mm_mul_ps(e, _mm_shuffle_ps(e, e, _MM_SHUFFLE(3, 0, 2, 1)));  // x y, y z, z x
  const float xy = _mm_cvtss_f32(p), yz = _mm_cvtss_f32(_mm_shuffle_ps(p, p, 1)),
              zx = _mm_cvtss_f32(_mm_shuffle_ps(p, p, 2));
  return 2.0f * ((xy + yz) + zx);
}

/// All lanes set (m true) or clear, as a mask for select4.
inline float4 mask4(bool m) { return _mm_castsi128_ps(_mm_set1_epi32(-int32_t(m))); }
/// Lane-wise: a where the mask's lane is set, else b (BLENDVPS: no branch).
inline float4 select4(float4 mask, float4 a, float4 b) { return _mm_blendv_ps(b, a, mask); }

/// Each lane truncated toward zero (CVTTPS2DQ; 0x80000000 for NaN and out-of-range lanes).
inline int4 truncate4(float4 v) { return _mm_cvttps_epi32(v); }

}  // namespace rp::simd
