#pragma once
/// Seeded motion for the update benchmarks (`raypack bench`, rp_bench): a smooth deformation
/// of every mesh and a jostle of every instance, scaled to the scene, so that refits and
/// instance-level rebuilds are timed on the same changes everywhere.

#include <span>
#include <vector>

#include "core/scene.h"

namespace rp {

/// `positions` moved smoothly: p + a * L * (sin 2pi(3 y/L + phase), sin 2pi(3 z/L + phase),
/// sin 2pi(3 x/L + phase)), L the diagonal of `box`, so neighbours move together (three waves
/// across the box) and no vertex moves by more than sqrt(3) a L. Computed in double.
std::vector<Vec3f> wobbled(Strided<Vec3f> positions, const Box3f& box, double amplitude, double phase);

/// Every mesh of `scene` set to its positions in `rest` (the same scene before any motion)
/// wobbled by `amplitude` of its box's diagonal there (Scene::set_vertices): frame `phase` of
/// an animation, so the motion does not build up from frame to frame.
void wobble_meshes(Scene& scene, const Scene& rest, double amplitude, double phase);

/// Every instance of `scene` set to its placement in `rest` moved by `amplitude` of its box's
/// diagonal along a direction and turned by 3 * amplitude turns about that axis through its
/// box's centre, the direction set by `phase` and the instance's index (Scene::set_transform):
/// a field of objects that all move between frames.
void jostle_instances(Scene& scene, const Scene& rest, double amplitude, double phase);

}  // namespace rp
