#pragma once
/// Small fixed-size vector math used by every part of raypack.
/// Vec3<T> is templated on the scalar so the same routines serve float (production) and
/// double (reference and test oracles).

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace rp {

/// Three-component vector; 12 bytes for float, 24 for double. No padding, no alignment.
template <typename T>
struct Vec3 {
  T x = 0, y = 0, z = 0;

  constexpr Vec3() = default;
  constexpr Vec3(T x_, T y_, T z_) : x(x_), y(y_), z(z_) {}
  constexpr explicit Vec3(T s) : x(s), y(s), z(s) {}
  template <typename U>
  constexpr explicit Vec3(const Vec3<U>& o) : x(T(o.x)), y(T(o.y)), z(T(o.z)) {}

  constexpr T operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr T& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }

  constexpr Vec3 operator-() const { return {-x, -y, -z}; }
  constexpr Vec3& operator+=(const Vec3& o) { x += o.x; y += o.y; z += o.z; return *this; }
  constexpr Vec3& operator-=(const Vec3& o) { x -= o.x; y -= o.y; z -= o.z; return *this; }
  constexpr Vec3& operator*=(T s) { x *= s; y *= s; z *= s; return *this; }
};

/// Component-wise equality (a template, not a defaulted member: Vec3 of an 8-lane type,
/// base/lanes.h, has no bool equality and must not be made to declare one).
template <typename T>
constexpr bool operator==(const Vec3<T>& a, const Vec3<T>& b) {
  return a.x == b.x && a.y == b.y && a.z == b.z;
}

using Vec3f = Vec3<float>;
using Vec3d = Vec3<double>;

/// Two-component vector (texture coordinates, image-plane points).
template <typename T>
struct Vec2 {
  T x = 0, y = 0;
  friend constexpr bool operator==(const Vec2&, const Vec2&) = default;
};
using Vec2f = Vec2<float>;

template <typename T> constexpr Vec3<T> operator+(Vec3<T> a, const Vec3<T>& b) { return a += b; }
template <typename T> constexpr Vec3<T> operator-(Vec3<T> a, const Vec3<T>& b) { return a -= b; }
template <typename T> constexpr Vec3<T> operator*(Vec3<T> a, T s) { return a *= s; }
template <typename T> constexpr Vec3<T> operator*(T s, Vec3<T> a) { return a *= s; }
template <typename T> constexpr Vec3<T> operator/(const Vec3<T>& a, T s) { return {a.x / s, a.y / s, a.z / s}; }
/// Component-wise product.
template <typename T> constexpr Vec3<T> mul(const Vec3<T>& a, const Vec3<T>& b) { return {a.x * b.x, a.y * b.y, a.z * b.z}; }

template <typename T> constexpr T dot(const Vec3<T>& a, const Vec3<T>& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
template <typename T> constexpr Vec3<T> cross(const Vec3<T>& a, const Vec3<T>& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <typename T> inline T length(const Vec3<T>& a) { return std::sqrt(dot(a, a)); }
/// Unit vector along a; a zero vector stays zero (never NaN from 0/0).
template <typename T> inline Vec3<T> normalize(const Vec3<T>& a) {
  T l = length(a);
  return l > T(0) ? a / l : a;
}
template <typename T> constexpr Vec3<T> min(const Vec3<T>& a, const Vec3<T>& b) {
  return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)};
}
template <typename T> constexpr Vec3<T> max(const Vec3<T>& a, const Vec3<T>& b) {
  return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)};
}
template <typename T> inline Vec3<T> abs(const Vec3<T>& a) { return {std::abs(a.x), std::abs(a.y), std::abs(a.z)}; }
template <typename T> constexpr T max_component(const Vec3<T>& a) { return std::max(a.x, std::max(a.y, a.z)); }
template <typename T> constexpr T min_component(const Vec3<T>& a) { return std::min(a.x, std::min(a.y, a.z)); }
/// Index (0, 1, 2) of the component with the largest absolute value; ties go to the lower index.
template <typename T> inline int max_abs_axis(const Vec3<T>& a) {
  Vec3<T> m = abs(a);
  return m.x >= m.y ? (m.x >= m.z ? 0 : 2) : (m.y >= m.z ? 1 : 2);
}
template <typename T> inline bool is_finite(const Vec3<T>& a) {
  return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}

/// Orthonormal basis around unit vector n (Duff et al. 2017, "Building an Orthonormal Basis,
/// Revisited", JCGT 6(1)); returns {t, b} with (t, b, n) right-handed.
template <typename T>
struct Basis {
  Vec3<T> t, b;
};
template <typename T> inline Basis<T> orthonormal_basis(const Vec3<T>& n) {
  T sign = std::copysign(T(1), n.z);
  T a = T(-1) / (sign + n.z);
  T b = n.x * n.y * a;
  return {{T(1) + sign * n.x * n.x * a, sign * b, -sign * n.x}, {b, sign + n.y * n.y * a, -n.y}};
}

inline constexpr double kPi = 3.14159265358979323846;

}  // namespace rp
