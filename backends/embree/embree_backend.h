#pragma once
/// The Embree 3 adapter. Only its files (backends/embree/) include <embree3/rtcore.h>.

#include <memory>
#include <string>
#include <vector>

#include "core/backend.h"
#include "core/scene.h"

namespace rp::embree {

/// Variants: "default" (Embree's fast intersectors, medium build quality), "robust"
/// (RTC_SCENE_FLAG_ROBUST: watertight-leaning triangle tests, conservative traversal),
/// "compact" (RTC_SCENE_FLAG_COMPACT: smaller BVH), "high" (RTC_BUILD_QUALITY_HIGH),
/// "dynamic" (for scenes that move: RTC_SCENE_FLAG_DYNAMIC, RTC_BUILD_QUALITY_LOW scenes, whose
/// two-level structure lets each geometry keep its own tree, and RTC_BUILD_QUALITY_REFIT
/// geometries, whose trees Backend::update() refits when their vertices move).
std::vector<std::string> variants();

/// Ways to trace a coherent span (BackendOptions::coherent_method): "packet8" (the default:
/// rtcIntersect8/rtcOccluded8), "packet16" (rtcIntersect16/rtcOccluded16: native only where
/// Embree runs its AVX-512 kernels, emulated otherwise), "stream" (the whole span as one
/// rtcIntersect1M/rtcOccluded1M stream with RTC_INTERSECT_CONTEXT_FLAG_COHERENT, which
/// Embree's documentation names the fastest mode for coherent rays).
std::vector<std::string> coherent_methods();

/// Ways to trace an incoherent batch (BackendOptions::incoherent_method): "single" (the
/// default: rtcIntersect1/rtcOccluded1 ray by ray, which Embree's documentation recommends
/// for incoherent rays) or "stream" (the batch as one rtcIntersect1M/rtcOccluded1M stream
/// without the coherent flag, which Embree traces as packets of consecutive rays; measured
/// faster than both on some shadow rays, so the benches time it too).
std::vector<std::string> incoherent_methods();

/// What Embree's default device says about itself.
struct DeviceFacts {
  std::string version;  ///< e.g. "3.13.5"
  std::string isa;      ///< the kernels it runs: inferred from the native packet widths and the CPU
  bool native_ray4 = false, native_ray8 = false, native_ray16 = false, stream = false;
};
DeviceFacts device_facts();

/// Builds an Embree scene over `scene`: one triangle geometry per world mesh; spheres, quadrics
/// and polygons as user geometry whose callbacks call core/geometry/ (world space only);
/// each instanced mesh a child scene of its own, built once, and each instance an
/// RTC_GEOMETRY_TYPE_INSTANCE geometry over it with the instance's object_to_world (Embree
/// inverts it itself, in float, to the bits of Instance::world_to_object: rp::float_inverse)
/// whose instID[0] names the instance; unbounded planes tested
/// beside the Embree scene. Backend::update(): moved vertices are copied into their
/// geometry's vertex buffer (rtcUpdateGeometryBuffer) and their scene committed again; moved
/// instances get their transforms (rtcSetGeometryTransform) and the top scene is committed;
/// anything added or removed builds every scene anew. Throws rp::Error on an Embree error or
/// an unknown variant.
std::unique_ptr<Backend> make_backend(const Scene& scene, const BackendOptions& options);

}  // namespace rp::embree
