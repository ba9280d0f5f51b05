#pragma once
/// Ray/plane intersection.

#include "base/math.h"
#include "core/geometry/intersection.h"
#include "core/ray.h"

namespace rp {

/// Hit of r with the plane n . P + d = 0 (n need not be unit length; both faces count).
/// t = -(n . org + d) / (n . dir), accepted when finite and in [r.tnear, r.tfar].
/// A ray parallel to the plane (n . dir == 0) misses, whether it lies in the plane or not.
/// u == v == 0. Miss: hit == false, t == +inf.
template <typename T>
Intersection<T> intersect_plane(const RayT<T>& r, const Vec3<T>& n, T d) {
  // Substitute P(t) = org + t*dir into n . P + d = 0 and solve for t (lecture notes,
  // "Ray-Plane Intersection", steps 1-2). NaN inputs give a NaN t, which is rejected.
  const T denom = dot(n, r.dir);
  if (denom == T(0)) return {};
  const T t = -(dot(n, r.org) + d) / denom;
  if (!in_ray_interval(r, t)) return {};
  return make_intersection(t);
}

}  // namespace rp
