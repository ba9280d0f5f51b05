#pragma once
/// The binary tree's collapse into 8-wide nodes: each node's row of the cost-optimal cut
/// (plan, run as the binary build finishes a node), then the layout of the nodes as it chose.
/// Internal to the builder (bvh8_*.cpp).

#include <cstdint>
#include <vector>

#include "backends/simd/bvh8.h"
#include "backends/simd/bvh8_build_node.h"

namespace rp::bvh8::build_detail {

/// The node's row of the cost-optimal collapse (Ylitie, Karras and Laine, "Efficient
/// Incoherent Ray Traversal on GPUs Through Compressed Wide BVHs", HPG 2017, sec. 4.1),
/// from its children's rows: the binary tree is cut into 8-wide nodes and leaves so that
/// the SAH cost is least, where an 8-wide node costs kTraversalCost times its area and a
/// leaf, one block test, (kLeafCost + kPrimCost * primitives) times its area. A subtree of
/// at most max_leaf primitives may become one leaf (its refs are contiguous), so small
/// sibling leaves merge into one block test, and nodes are filled by cost rather than
/// opened greedily. Runs in the (parallel) build as children finish; the result depends on
/// the tree only, so it stays deterministic. `max_leaf`: BuildOptions::max_leaf.
void plan(BuildNode& n, uint32_t max_leaf);

/// A leaf: its primitives refs[ref, ref + count) and its offset in leaf_data (in its
/// chunk's buffer until write_leaves copies it).
struct PlacedLeaf {
  uint32_t ref, count, offset;
};

/// Lays the binary tree out as 8-wide nodes and leaves, cut as plan chose
/// (depth-first, single-threaded, so the layout is deterministic).
///
/// Lays the tree out: the nodes over subtrees of at least kSubtree refs in one thread, then
/// those subtrees in parallel, each at the places its counts give (counted in parallel
/// too), so the layout is the same whatever the thread count. The binary tree's nodes
/// are read once more per subtree (to count), but by all threads: walking them is a chain
/// of cache misses. Returns the leaves, numbered as the nodes' leaf children
/// number them (each holds its number where its offset will go, see write_leaves).
std::vector<PlacedLeaf> collapse(const BuildNode& root, Bvh8& out);

}  // namespace rp::bvh8::build_detail
