#pragma once
// What the core/geometry/ tests share (tests/engine/geometry/): rays in any precision, closeness,
// seeded random vectors, and the tables of triangle and sphere routines that property tests
// run side by side.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "base/bbox.h"
#include "base/math.h"
#include "core/geometry/intersection.h"
#include "core/geometry/plane.h"
#include "core/geometry/polygon.h"
#include "core/geometry/quadric.h"
#include "core/geometry/slab.h"
#include "core/geometry/sphere.h"
#include "core/geometry/triangle.h"
#include "core/ray.h"

namespace rp::test {

using L = long double;

template <typename T>
constexpr T kInfT = std::numeric_limits<T>::infinity();
template <typename T>
constexpr T kNanT = std::numeric_limits<T>::quiet_NaN();

template <typename T>
RayT<T> make_ray(const Vec3<T>& o, const Vec3<T>& d, T tnear = T(0), T tfar = kInfT<T>) {
  RayT<T> r;
  r.org = o;
  r.dir = d;
  r.tnear = tnear;
  r.tfar = tfar;
  return r;
}

template <typename T>
std::span<const Vec3<T>> as_span(const std::vector<Vec3<T>>& v) {
  return {v.data(), v.size()};
}

/// |a - b| <= rel * max(1, |a|, |b|); infinities are close only to themselves.
template <typename T>
bool close_rel(T a, T b, T rel) {
  if (std::isinf(a) || std::isinf(b)) return a == b;
  return std::abs(a - b) <= rel * std::max({T(1), std::abs(a), std::abs(b)});
}

template <typename T>
Vec3<T> uniform_vec(std::mt19937& rng, T lo, T hi) {
  std::uniform_real_distribution<T> u(lo, hi);
  const T x = u(rng);
  const T y = u(rng);
  const T z = u(rng);
  return {x, y, z};
}

template <typename T>
Vec3<T> unit_vec(std::mt19937& rng) {
  std::normal_distribution<T> n(T(0), T(1));
  for (;;) {
    const T x = n(rng);
    const T y = n(rng);
    const T z = n(rng);
    const Vec3<T> v{x, y, z};
    if (dot(v, v) > T(1e-6)) return normalize(v);
  }
}

template <typename T>
T uniform(std::mt19937& rng, T lo, T hi) {
  return std::uniform_real_distribution<T>(lo, hi)(rng);
}

/// The triangle and sphere routines of core/geometry, named, for tests that run them all.

template <typename T>
using TriangleFn = Intersection<T> (*)(const RayT<T>&, const Vec3<T>&, const Vec3<T>&,
                                       const Vec3<T>&);
template <typename T>
struct TriangleMethod {
  const char* name;
  TriangleFn<T> fn;
};
template <typename T>
std::array<TriangleMethod<T>, 5> triangle_methods() {
  return {{{"moller_trumbore", &intersect_triangle_mt<T>},
           {"moller_trumbore_normal", &intersect_triangle_mt_normal<T>},
           {"cramer", &intersect_triangle_cramer<T>},
           {"two_step", &intersect_triangle_two_step<T>},
           {"watertight", &intersect_triangle_watertight<T>}}};
}

template <typename T>
using SphereFn = Intersection<T> (*)(const RayT<T>&, const Vec3<T>&, T);
template <typename T>
struct SphereMethod {
  const char* name;
  SphereFn<T> fn;
};
template <typename T>
std::array<SphereMethod<T>, 3> sphere_methods() {
  return {{{"algebraic", &intersect_sphere_algebraic<T>},
           {"geometric", &intersect_sphere_geometric<T>},
           {"naive", &intersect_sphere_naive<T>}}};
}


/// A sphere and a ray for the sphere and quadric property tests, and what makes its answer
/// hard (tangency, an origin on the surface).
template <typename T>
struct SphereCase {
  Vec3<T> c;
  T radius;
  RayT<T> ray;
};

/// Origin outside (kind 0), inside (kind 1) or within rounding of the surface (kind 2);
/// direction aimed within 1.3 radii of the center, random length.
template <typename T>
SphereCase<T> random_sphere_case(std::mt19937& rng, int kind) {
  SphereCase<T> s;
  s.c = uniform_vec<T>(rng, -5, 5);
  s.radius = uniform<T>(rng, 0.1, 3);
  const T dist = kind == 0 ? uniform<T>(rng, 1.01, 8) : (kind == 1 ? uniform<T>(rng, 0, 0.99) : 1);
  const Vec3<T> o = s.c + unit_vec<T>(rng) * (s.radius * dist);
  const Vec3<T> target = s.c + unit_vec<T>(rng) * (s.radius * uniform<T>(rng, 0, 1.3));
  s.ray = make_ray(o, (target - o) * uniform<T>(rng, 0.1, 10));
  if (rng() % 4 == 0) s.ray.tnear = -kInfT<T>;
  return s;
}

struct SphereReference {
  L tangency;  // |r^2 - dist^2| / r^2, small for grazing rays
  L surface;   // ||f|^2 - r^2| / r^2, small for origins on the surface
  L scale;     // (|f| + r) / |d|: the t scale of the problem
};

template <typename T>
SphereReference sphere_reference(const SphereCase<T>& s) {
  const Vec3<L> f = Vec3<L>(s.ray.org) - Vec3<L>(s.c), d(s.ray.dir);
  const L r2 = L(s.radius) * L(s.radius);
  const L a = dot(d, d), b = dot(f, d);
  const L dist2 = dot(f, f) - b * b / a;
  return {std::abs(r2 - dist2) / r2, std::abs(dot(f, f) - r2) / r2,
          (length(f) + L(s.radius)) / std::sqrt(a)};
}

/// The case's answer in long double (the algebraic method, exact inputs widened): the oracle
/// the sphere tests compare every method against.
template <typename T>
Intersection<L> sphere_oracle(const SphereCase<T>& s) {
  return intersect_sphere_algebraic(RayT<L>{Vec3<L>(s.ray.org), s.ray.tnear, Vec3<L>(s.ray.dir), s.ray.tfar},
                                    Vec3<L>(s.c), L(s.radius));
}

}  // namespace rp::test
