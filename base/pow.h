#pragma once
/// x^y for x >= 0 and y >= 0 (Blinn-Phong's cos^shininess), worked out in double precision
/// by one fixed sequence of operations, so that the 8-wide twin (simd/pow8.h) gives every
/// lane the same bits. Against libm's powf it differs by at most 1 ulp (tested): both are
/// within an ulp of the exact power, and they differ only where libm's is not correctly
/// rounded or where the exact power lies within 2^-40 ulp of a rounding boundary.
///
/// Method: x = m 2^e with m in (sqrt(1/2), sqrt(2)); log2(m) = (2 / ln 2) atanh(s), s = (m - 1)
/// / (m + 1), |s| < 0.1716, by its odd series to s^17 (truncation < 2^-50); z = y (e + log2 m);
/// 2^z = 2^n e^(f ln 2), n = z rounded to nearest even, |f| <= 1/2, by Taylor to degree 13
/// (truncation < 2^-56); then one rounding to float. The float result is therefore within
/// 2^-24 (1/2 ulp) plus y 2^-49 relative of the exact power.

#include <bit>
#include <cmath>
#include <cstdint>

namespace rp {

namespace pow_detail {

/// log2(m) = s * sum_k kLog2[k] s^(2k): 2 / (ln 2 (2k + 1)).
inline constexpr double kLog2[9] = {
    2.0 / 0.69314718055994530942 / 1.0,  2.0 / 0.69314718055994530942 / 3.0,  2.0 / 0.69314718055994530942 / 5.0,
    2.0 / 0.69314718055994530942 / 7.0,  2.0 / 0.69314718055994530942 / 9.0,  2.0 / 0.69314718055994530942 / 11.0,
    2.0 / 0.69314718055994530942 / 13.0, 2.0 / 0.69314718055994530942 / 15.0, 2.0 / 0.69314718055994530942 / 17.0};
/// e^t = sum_k t^k / k!, k = 0..13.
inline constexpr double kExp[14] = {1.0,
                                    1.0,
                                    1.0 / 2.0,
                                    1.0 / 6.0,
                                    1.0 / 24.0,
                                    1.0 / 120.0,
                                    1.0 / 720.0,
                                    1.0 / 5040.0,
                                    1.0 / 40320.0,
                                    1.0 / 362880.0,
                                    1.0 / 3628800.0,
                                    1.0 / 39916800.0,
                                    1.0 / 479001600.0,
                                    1.0 / 6227020800.0};
inline constexpr double kLn2 = 0.69314718055994530942;
/// Beyond these the power is 0 or +inf in float for certain (and 2^n stays a normal double).
inline constexpr double kMinExponent = -1000.0, kMaxExponent = 1000.0;
inline constexpr float kSqrt2 = 1.41421356f;  ///< the float nearest sqrt(2), above it

}  // namespace pow_detail

/// x^y for x >= 0 and y >= 0, both finite (the caller's domain; 0^0 = 1, 0^y = 0). Any other
/// input goes to std::pow.
inline float pow_nonneg(float x, float y) {
  using namespace pow_detail;
  if (!(x >= 0.0f && y >= 0.0f && x <= 3.0e38f && y <= 3.0e38f)) return std::pow(x, y);
  if (y == 0.0f) return 1.0f;
  if (x == 0.0f) return 0.0f;
  // x = m 2^e, a denormal scaled up first (exactly).
  const bool tiny = x < 0x1p-126f;
  const uint32_t bits = std::bit_cast<uint32_t>(tiny ? x * 0x1p24f : x);
  int e = int(bits >> 23) - 127 - (tiny ? 24 : 0);
  float m = std::bit_cast<float>((bits & 0x007fffffu) | 0x3f800000u);
  if (m > kSqrt2) {
    m *= 0.5f;
    e += 1;
  }
  const double md = double(m), s = (md - 1.0) / (md + 1.0), s2 = s * s;
  double p = kLog2[8];
  for (int k = 7; k >= 0; --k) p = std::fma(p, s2, kLog2[k]);
  double z = double(y) * std::fma(s, p, double(e));
  z = std::fmin(std::fmax(z, kMinExponent), kMaxExponent);
  const double n = std::nearbyint(z), t = (z - n) * kLn2;
  double q = kExp[13];
  for (int k = 12; k >= 0; --k) q = std::fma(q, t, kExp[k]);
  const double scale = std::bit_cast<double>(uint64_t(int64_t(n) + 1023) << 52);
  return float(q * scale);
}

}  // namespace rp
