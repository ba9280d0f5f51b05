#pragma once
/// The hand-written 8-wide backend ("simd"): an 8-wide BVH (bvh8.h) traversed by packets of 8
/// coherent rays or by single rays against 8 child boxes at once. No SIMD types here: the
/// registry includes this header from a translation unit built without AVX2.

#include <memory>
#include <string>
#include <vector>

#include "core/backend.h"
#include "core/scene.h"

namespace rp::bvh8 {

/// Variants: "default" (binned SAH build, Möller–Trumbore), "median" (the lecture notes' rule: longest
/// axis, centroid median, balanced), "watertight" (SAH build, Möller–Trumbore with a forward
/// error bound and exact edge decisions where it is uncertain, watertight.h: no ray passes
/// between triangles that share an edge or a vertex),
/// "spatial" (SAH build with spatial splits, BuildOptions::spatial_splits; Möller–Trumbore: the
/// same hits as "default", a tree with less overlap where triangles are long and thin, built
/// more slowly). Every variant traverses with conservative (padded) box tests.
std::vector<std::string> variants();

/// Ways to trace a coherent span (BackendOptions::coherent_method): "large" (the default: up
/// to 64 packets of one direction octant traverse as one large packet, large_packet.h) and
/// "packet8" (independent 8-ray packets).
std::vector<std::string> coherent_methods();

/// Ways to trace an incoherent batch (BackendOptions::incoherent_method): "stream" (the
/// default: the batch goes down the tree as a ray stream, stream.h) and "single" (ray by ray).
std::vector<std::string> incoherent_methods();

/// Builds the backend; the caller (the registry) has checked that the CPU has AVX2 and FMA.
/// Throws rp::Error for an unknown variant or coherent method.
std::unique_ptr<Backend> make_backend(const Scene& scene, const BackendOptions& options);

}  // namespace rp::bvh8
