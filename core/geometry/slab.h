#pragma once
/// Scalar reference ray/box test (slab method), robust to zero, signed-zero and infinite
/// direction components.

#include <cmath>
#include <limits>

#include "base/bbox.h"
#include "base/math.h"
#include "core/ray.h"

namespace rp {

/// Parameter interval [t_min, t_max] in which a ray is inside one slab lo <= x <= hi.
/// t_min > t_max (+inf, -inf) when the ray never is. Never NaN.
template <typename T>
struct SlabInterval {
  T t_min, t_max;
};

/// Result of a ray/box test.
/// hit: the slab interval [t_enter, t_exit] is non-empty and overlaps [r.tnear, r.tfar].
/// t_enter / t_exit on a hit: the raw slab values (max of the per-axis entries, min of the
/// per-axis exits), NOT clamped to [tnear, tfar]; they may be infinite, never NaN.
/// Miss: hit == false, t_enter == +inf, t_exit == -inf.
template <typename T>
struct SlabHit {
  bool hit = false;
  T t_enter = std::numeric_limits<T>::infinity();
  T t_exit = -std::numeric_limits<T>::infinity();
};

/// Slab interval of the 1D ray x(t) = org + t*dir against [lo, hi] (closed), by the lecture notes'
/// formula t = (face - org) / dir with the swap. Preconditions: org finite, no NaN.
/// dir == +-0: the whole line (-inf, +inf) when lo <= org <= hi, else empty.
/// dir == +-inf: each finite face is crossed at t = 0 (the limit of ever larger dir), so the
/// interval is [0, 0] (or half-infinite for an infinite face).
template <typename T>
SlabInterval<T> slab_interval(T org, T dir, T lo, T hi) {
  constexpr T inf = std::numeric_limits<T>::infinity();
  // Parallel to the slab: inside (closed) -> no constraint, outside -> empty (lecture notes "Ray-Surface Intersection",
  // "Ray-AABB Intersection: Slab Method, Edge Case"), decided by comparison instead of the
  // 0/0 the plain formula would give for an origin on a face.
  if (dir == T(0)) {
    if (lo <= org && org <= hi) return {-inf, inf};
    return {inf, -inf};
  }
  // (face - org) / dir is NaN only for an infinite face with an infinite dir; its limit is
  // an infinity with the product sign.
  const auto face_t = [&](T face) {
    const T t = (face - org) / dir;
    return t == t ? t : std::copysign(inf, face - org) * std::copysign(T(1), dir);
  };
  T t0 = face_t(lo);
  T t1 = face_t(hi);
  if (t0 > t1) {
    const T tmp = t0;
    t0 = t1;
    t1 = tmp;
  }
  return {t0, t1};
}

/// Ray/box test against the closed box b. See SlabHit for the result.
/// A NaN anywhere in the ray or the box, or a non-finite origin, is a miss. An empty box
/// (lo > hi on some axis) is a miss. Directions may contain +-0 and +-inf (see
/// slab_interval).
template <typename T>
SlabHit<T> intersect_box(const RayT<T>& r, const Box3<T>& b) {
  // Kay & Kajiya 1986, "Ray Tracing Complex Scenes", SIGGRAPH; in the lecture notes' form (lecture
  // notes, "Ray-AABB Intersection: Slab Method, Algorithm", steps 1-4), with the overlap
  // against [tnear, tfar] instead of t_exit >= 0.
  if (!is_finite(r.org) || r.dir.x != r.dir.x || r.dir.y != r.dir.y || r.dir.z != r.dir.z ||
      r.tnear != r.tnear || r.tfar != r.tfar) {
    return {};
  }
  T t_enter = -std::numeric_limits<T>::infinity();
  T t_exit = std::numeric_limits<T>::infinity();
  for (int k = 0; k < 3; ++k) {
    if (!(b.lo[k] <= b.hi[k])) return {};  // empty or NaN
    const SlabInterval<T> s = slab_interval(r.org[k], r.dir[k], b.lo[k], b.hi[k]);
    if (s.t_min > t_enter) t_enter = s.t_min;
    if (s.t_max < t_exit) t_exit = s.t_max;
  }
  if (!(t_enter <= t_exit && t_enter <= r.tfar && t_exit >= r.tnear)) return {};
  return {true, t_enter, t_exit};
}

}  // namespace rp
