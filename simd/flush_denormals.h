#pragma once
/// The floating-point mode Embree asks of every thread that calls it: flush-to-zero and
/// denormals-are-zero in MXCSR. SSE only, so unlike float8.h and float4.h this header runs on
/// any x86-64 CPU and needs no ISA flags.

#include <xmmintrin.h>

namespace rp::simd {

/// Sets flush-to-zero and denormals-are-zero for the calling thread while it lives; the
/// caller's MXCSR is restored afterwards.
class FlushDenormals {
 public:
  FlushDenormals() : saved_(_mm_getcsr()) { _mm_setcsr(saved_ | kFtzDaz); }
  ~FlushDenormals() { _mm_setcsr(saved_); }
  FlushDenormals(const FlushDenormals&) = delete;
  FlushDenormals& operator=(const FlushDenormals&) = delete;

 private:
  static constexpr unsigned int kFtzDaz = 0x8040u;  ///< MXCSR bits 15 (flush to zero) and 6 (denormals are zero)
  unsigned int saved_;
};

}  // namespace rp::simd
