#pragma once
/// Result of one ray/primitive test, shared by every routine in core/geometry.
///
/// Conventions that hold for every intersect_* routine in core/geometry/ (intersect_box in
/// slab.h returns a SlabHit interval instead, see there):
/// - A root t counts only when r.tnear <= t <= r.tfar (both ends closed) and t is finite;
///   a hit at t = +inf is never reported, because rp::Hit uses t = +inf to mean "miss".
/// - When several roots lie in that interval the smallest one is returned.
/// - A NaN in the ray or in the primitive never yields a hit: every acceptance test is
///   written as "accept when the comparison holds", so a NaN fails it.
/// - Directions are not normalized; t is in units of the direction's length.

#include <cmath>
#include <limits>

#include "base/math.h"
#include "core/ray.h"

namespace rp {

/// Closest accepted hit of one ray with one primitive.
/// On a miss: hit == false, t == +inf, u == v == 0.
/// (u, v) by primitive:
/// - triangle: Embree's barycentrics, point = (1-u-v)*v0 + u*v1 + v*v2, u, v >= 0, u+v <= 1;
/// - sphere: u = phi/(2*pi) in [0, 1) with phi = atan2(z, x) of (p - c) measured from +x
///   towards +z, v = theta/pi in [0, 1] with theta the angle from +y (v = 0 at the +y pole);
/// - plane, quadric, polygon: u == v == 0.
template <typename T>
struct Intersection {
  bool hit = false;
  T t = std::numeric_limits<T>::infinity();
  T u = 0, v = 0;
};

/// True when t is an acceptable hit parameter for r: finite and r.tnear <= t <= r.tfar.
/// False for NaN t or NaN interval ends.
template <typename T>
constexpr bool in_ray_interval(const RayT<T>& r, T t) {
  return t >= r.tnear && t <= r.tfar && t > -std::numeric_limits<T>::infinity() &&
         t < std::numeric_limits<T>::infinity();
}

/// A hit at t with surface parameters (u, v).
template <typename T>
constexpr Intersection<T> make_intersection(T t, T u = T(0), T v = T(0)) {
  return {true, t, u, v};
}

/// Calls f(h) for each hit h of one primitive along r within [tnear, tfar], in order of t,
/// where test(ray) gives the primitive's closest hit of a ray (an intersect_* routine): after
/// each hit the search goes on from the next representable t, so a sphere or quadric crossed
/// twice gives both roots, a root is reported once (a double root too) and a triangle, polygon
/// or plane one hit. Stops when f returns true, and then returns true. The one rule by which
/// every query that lists hits (all_hits, count_hits, filters) finds the roots of a primitive.
template <typename T, class Test, class F>
bool for_each_root(const RayT<T>& r, Test&& test, F&& f) {
  RayT<T> rest = r;
  for (int k = 0; k < 4; ++k) {  // at most two roots, and a polygon's one hit
    const Intersection<T> h = test(rest);
    if (!h.hit) return false;
    if (f(h)) return true;
    rest.tnear = std::nextafter(h.t, std::numeric_limits<T>::infinity());
    if (!(rest.tnear <= rest.tfar)) return false;
  }
  return false;
}

}  // namespace rp
