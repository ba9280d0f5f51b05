#pragma once
/// Moving a secondary ray's origin off the surface it leaves.

#include <bit>
#include <cmath>
#include <cstdint>

#include "base/math.h"

namespace rp {

/// Offsets hit point p along the (face-forwarded, unit) normal n by a fixed number of ulps of
/// each coordinate, or by a fixed distance near the origin where ulps are tiny: Wächter and
/// Binder, "A Fast and Robust Method for Avoiding Self-Intersection", Ray Tracing Gems (2019),
/// ch. 6. Scale-independent: the offset grows with |p| exactly as float spacing does.
namespace offset_detail {
inline constexpr float kOrigin = 1.0f / 32.0f;       ///< below this |coordinate|, a fixed distance
inline constexpr float kFloatScale = 1.0f / 65536.0f;  ///< that distance per unit of normal
inline constexpr float kIntScale = 256.0f;           ///< ulps per unit of normal elsewhere
}  // namespace offset_detail

inline Vec3f offset_ray_origin(const Vec3f& p, const Vec3f& n) {
  using namespace offset_detail;
  Vec3f out;
  for (int a = 0; a < 3; ++a) {
    const int32_t of = int32_t(kIntScale * n[a]);
    const int32_t bits = std::bit_cast<int32_t>(p[a]);
    const float pi = std::bit_cast<float>(bits + (p[a] < 0.0f ? -of : of));
    out[a] = std::abs(p[a]) < kOrigin ? p[a] + kFloatScale * n[a] : pi;
  }
  return out;
}

}  // namespace rp
