#pragma once
/// The Embree 3 adapter. Only embree_backend.cpp includes <embree3/rtcore.h>.

#include <memory>
#include <string>
#include <vector>

#include "engine/backend.h"
#include "engine/scene.h"

namespace rp::embree {

/// Variants: "default" (Embree's fast intersectors, medium build quality), "robust"
/// (RTC_SCENE_FLAG_ROBUST: watertight-leaning triangle tests, conservative traversal),
/// "compact" (RTC_SCENE_FLAG_COMPACT: smaller BVH), "high" (RTC_BUILD_QUALITY_HIGH).
std::vector<std::string> variants();

/// Builds an Embree scene over `scene`: one triangle geometry per mesh; spheres, quadrics and
/// polygons as user geometry whose callbacks call engine/geometry; unbounded planes tested
/// beside the Embree scene. Throws rp::Error on an Embree error or an unknown variant.
std::unique_ptr<Backend> make_backend(const Scene& scene, const BackendOptions& options);

}  // namespace rp::embree
