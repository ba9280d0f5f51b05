#pragma once
/// Moving and scaling a whole scene, for the stability families that test methods far from the
/// origin and at extreme scales (analysis/stability.h).

#include "base/math.h"
#include "core/scene.h"

namespace rp {

/// A copy of `scene` with every position p replaced by round(scale * p + offset) (computed in
/// double): world meshes, spheres, quadrics (coefficients rescaled), polygons, planes, lights
/// and camera; instanced meshes stay in their object space and each instance's transform is
/// composed with the move (in double, rounded to float). The geometry the methods see is then the float rounding of the moved scene. Throws
/// rp::Error unless scale is finite and > 0.
Scene transformed(const Scene& scene, double scale, const Vec3d& offset);

}  // namespace rp
