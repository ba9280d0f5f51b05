#pragma once
/// Rays and hits: the data that crosses the backend seam, as spans of Ray in and spans of Hit
/// out (core/backend.h). Packets are each backend's own layout and never cross it.
///
/// Hit convention (every backend, every routine): a surface point at parameter t counts
/// only when tnear <= t <= tfar (both ends closed). Directions are never normalized by
/// raypack: t is in units of the direction's length.

#include <cmath>
#include <cstdint>
#include <limits>

#include "base/math.h"

namespace rp {

/// A ray P(t) = org + t * dir restricted to [tnear, tfar]. 32 bytes for float.
template <typename T>
struct RayT {
  Vec3<T> org;
  T tnear = 0;
  Vec3<T> dir;
  T tfar = std::numeric_limits<T>::infinity();

  constexpr Vec3<T> at(T t) const { return org + dir * t; }
};
using Ray = RayT<float>;
using Rayd = RayT<double>;

/// The range every backend traces exactly, shared by the backends, the reference, the
/// renderer and the scene loaders (README, "Valid rays and scenes"):
/// - positions: every scene coordinate (vertices, sphere and quadric boxes, polygon
///   vertices, plane offsets, lights, camera points) and every ray origin component lies in
///   [-kMaxCoordinate, kMaxCoordinate], 2^30 = 1073741824;
/// - directions: the largest |component| of a ray direction lies in [kMinDirection,
///   kMaxDirection] = [2^-26, 2^31], so the difference of any two positions in range is a
///   valid direction.
/// Why these bounds: the float kernels are polynomials of degree 3 in the coordinates and
/// divide by the direction's largest component, and every intermediate must stay finite.
/// With positions <= 2^30 and directions in [2^-26, 2^31]: Möller–Trumbore's T = Ng.(v0 - o)
/// stays below 2^97; the watertight test's scaled distance U * Az below 2^124 (Az <= 2P/d_min);
/// the sphere's a * disc below 2^124; the quadric's terms below 2^75 once its coefficients
/// and the direction are scaled by powers of two (exactly: quadric.h); all below float's
/// 2^128. Embree asserts (and aborts) beyond 1.844e18; the rule stays far inside that.
/// Scenes beyond the range are refused at load; rays beyond it are misses everywhere.
inline constexpr float kMaxCoordinate = 0x1p30f;
inline constexpr float kMinDirection = 0x1p-26f;
inline constexpr float kMaxDirection = 0x1p31f;

/// True when every component of p is finite and within [-kMaxCoordinate, kMaxCoordinate].
template <typename T>
constexpr bool in_coordinate_range(const Vec3<T>& p) {
  return std::abs(p.x) <= T(kMaxCoordinate) && std::abs(p.y) <= T(kMaxCoordinate) &&
         std::abs(p.z) <= T(kMaxCoordinate);  // false for NaN
}

/// True when the largest |component| of d is within [kMinDirection, kMaxDirection] (false
/// for a zero, infinite or NaN component).
template <typename T>
constexpr bool in_direction_range(const Vec3<T>& d) {
  const T m = std::max(std::abs(d.x), std::max(std::abs(d.y), std::abs(d.z)));
  return m >= T(kMinDirection) && m <= T(kMaxDirection) && d.x == d.x && d.y == d.y && d.z == d.z;
}

/// The one validity rule (see above): origin in the coordinate range, direction in the
/// direction range, 0 <= tnear <= tfar (tfar may be +inf; NaN ends are invalid). Every backend
/// and the reference report any other ray as a miss and as not occluded, and never pass it
/// to an engine.
template <typename T>
constexpr bool valid_ray(const RayT<T>& r) {
  return in_coordinate_range(r.org) && in_direction_range(r.dir) && r.tnear >= T(0) && r.tnear <= r.tfar;
}

/// prim_id of a miss.
inline constexpr uint32_t kInvalidId = 0xffffffffu;

/// instance_id of a hit on a primitive that no instance places: a world-space triangle of a
/// mesh placed as it is, an analytic primitive, a plane, and a miss.
inline constexpr uint32_t kNoInstance = 0xffffffffu;

/// Closest (or any) hit of one ray. 20 bytes: today's 16 (t, prim_id, u, v), which the
/// renderer's 8-wide shading reads as 4-float records (at a 20-byte stride), then the instance.
/// On a miss: prim_id == kInvalidId, t == +inf, u == v == 0, instance_id == kNoInstance.
/// prim_id is the scene's flat numbering (core/scene.h); a triangle of an instanced mesh
/// keeps its mesh's prim_id in every placement, and instance_id (an index into
/// Scene::instances()) says which placement was hit. (u, v) and t are the same in the
/// instance's object space and in the world: an affine map keeps both (see Scene::instances).
/// For triangles (u, v) are Embree's barycentrics: p = (1-u-v)*v0 + u*v1 + v*v2. For analytic
/// primitives they are the primitive's surface parameters in [0, 1] (see core/geometry).
struct Hit {
  float t = std::numeric_limits<float>::infinity();
  uint32_t prim_id = kInvalidId;
  float u = 0, v = 0;
  uint32_t instance_id = kNoInstance;

  constexpr bool hit() const { return prim_id != kInvalidId; }
};
static_assert(sizeof(Hit) == 20);

/// The caller's promise about a batch, used by backends to pick packet (coherent) or
/// single-ray (incoherent) traversal. Primary rays from 4x2 pixel blocks are coherent;
/// diffuse bounces are not.
enum class Coherence : uint8_t { coherent, incoherent };

}  // namespace rp
