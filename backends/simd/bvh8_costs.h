#pragma once
/// The SAH costs the builder weighs: the binary build's split or leaf, the collapse's node or
/// leaf, and the tree's reported cost (BuildStats::sah_cost). Internal to the builder.

#include <cstdint>

#include "backends/simd/bvh8.h"

namespace rp::bvh8::build_detail {

constexpr float kTraversalCost = 1.0f;      ///< SAH cost of visiting a node
constexpr float kIntersectionCost = 0.15f;  ///< binary build: SAH cost of one primitive test (8-wide leaf tests: cheap)
constexpr float kLeafCost = 0.5f;           ///< collapse: SAH cost of one leaf's block test...
constexpr float kPrimCost = 0.1f;           ///< ...plus this per primitive in it
/// A node of at most this many primitives that may be a leaf is one, whatever its best split
/// (leaf_cheaper: kIntersectionCost * n <= kTraversalCost <= a split's cost), so it is not
/// binned: a large share of the binary tree's nodes on the measured meshes (figures:
/// docs/notes/2026-11-29-figures-from-code-comments.md).
constexpr uint32_t kAlwaysLeaf = uint32_t(kTraversalCost / kIntersectionCost);
static_assert(kIntersectionCost * float(kAlwaysLeaf) <= kTraversalCost);

/// SAH cost of the 8-wide tree `t` (BuildStats::sah_cost).
double sah_cost(const Bvh8& t);

}  // namespace rp::bvh8::build_detail
