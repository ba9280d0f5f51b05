#pragma once
/// A cache hint shared by the kernels (float8.h) and the builder (float4.h).

#include <immintrin.h>

namespace rp::simd {

/// Starts loading the cache line holding `p` into L1 (a hint: no fault, no wait).
inline void prefetch(const void* p) { _mm_prefetch(static_cast<const char*>(p), _MM_HINT_T0); }

}  // namespace rp::simd
