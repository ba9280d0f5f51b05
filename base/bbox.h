#pragma once
/// Axis-aligned bounding boxes.

#include <cmath>
#include <limits>

#include "base/math.h"

namespace rp {

/// Closed box [lo, hi]. The default box is empty (lo = +inf, hi = -inf) so that extending
/// it by any point or box yields that point or box.
template <typename T>
struct Box3 {
  Vec3<T> lo{std::numeric_limits<T>::infinity()};
  Vec3<T> hi{-std::numeric_limits<T>::infinity()};

  constexpr Box3() = default;
  constexpr Box3(const Vec3<T>& lo_, const Vec3<T>& hi_) : lo(lo_), hi(hi_) {}

  constexpr void extend(const Vec3<T>& p) { lo = min(lo, p); hi = max(hi, p); }
  constexpr void extend(const Box3& b) { lo = min(lo, b.lo); hi = max(hi, b.hi); }
  constexpr bool empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
  constexpr Vec3<T> extent() const { return hi - lo; }
  constexpr Vec3<T> center() const { return (lo + hi) * T(0.5); }
  constexpr bool contains(const Vec3<T>& p) const {
    return p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y && p.z >= lo.z && p.z <= hi.z;
  }
  /// Surface area; 0 for an empty box.
  constexpr T area() const {
    if (empty()) return T(0);
    Vec3<T> e = extent();
    return T(2) * (e.x * e.y + e.y * e.z + e.z * e.x);
  }
  friend constexpr bool operator==(const Box3&, const Box3&) = default;
};

using Box3f = Box3<float>;
using Box3d = Box3<double>;

/// Largest float <= x (x not NaN).
inline float round_down(double x) {
  float f = float(x);
  if (double(f) > x) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}

/// Smallest float >= x (x not NaN).
inline float round_up(double x) {
  float f = float(x);
  if (double(f) < x) f = std::nextafter(f, std::numeric_limits<float>::infinity());
  return f;
}

/// The smallest float box containing the double box b grown by pad on every side.
inline Box3f outward(const Box3d& b, double pad = 0.0) {
  Box3f f;
  for (int k = 0; k < 3; ++k) {
    f.lo[k] = round_down(b.lo[k] - pad);
    f.hi[k] = round_up(b.hi[k] + pad);
  }
  return f;
}

}  // namespace rp
