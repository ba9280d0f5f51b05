#pragma once
/// The binary build tree's node, the arena its nodes live in, and which subtrees may become
/// one leaf. Internal to the builder (bvh8_*.cpp).

#include <cstddef>
#include <cstdint>
#include <vector>

#include "backends/simd/bvh8.h"

namespace rp::bvh8::build_detail {

/// Binary build tree: a leaf has no children and owns refs[begin, end). Each node also carries
/// its row of the cost-optimal collapse into 8-wide nodes (see plan, bvh8_collapse.h). Nodes
/// live in a NodeArena.
struct BuildNode {
  Box3f box;
  uint32_t begin, end;
  BuildNode *left, *right;
  bool leaf() const { return !left; }
  uint32_t count() const { return end - begin; }

  /// cost[i - 1]: least SAH cost of the subtree as at most i children of an 8-wide node
  /// (i = 1..8); split[i - 1] (i >= 2): how many of them come from the left child, or 0 when
  /// i - 1 children do as well. With one child the subtree is one leaf (as_leaf) or one
  /// 8-wide node of node_width children, node_split of them from the left.
  float cost[8];
  uint8_t split[8];
  uint8_t node_width, node_split;
  bool as_leaf;
  bool analytic;  ///< holds an analytic primitive (see may_leaf)
};
/// Blocks of build nodes, one arena per thread (no allocation per node; the nodes die with
/// the build). Which arena holds a node does not matter: only the pointers are the tree.
class NodeArena {
 public:
  BuildNode* make() {
    if (used_ == kBlock) {
      blocks_.emplace_back(kBlock);
      used_ = 0;
    }
    return &blocks_.back()[used_++];
  }

 private:
  static constexpr size_t kBlock = (size_t(2) << 20) / sizeof(BuildNode);  ///< one huge page
  std::vector<std::vector<BuildNode, HugePageAllocator<BuildNode>>> blocks_;
  size_t used_ = kBlock;
};

/// Whether the subtree may be one leaf: at most max_leaf primitives, and an analytic
/// primitive only alone. A leaf's box is the only cull before a primitive's test, and a
/// quadric sharing a leaf with triangles would be tested by every ray that reaches them
/// (on the default scene, measured, several times as many scalar analytic tests as Embree,
/// whose user geometry has a box per primitive).
inline bool may_leaf(const BuildNode& n, uint32_t max_leaf) {
  return n.count() <= max_leaf && (n.count() == 1 || !n.analytic);
}

}  // namespace rp::bvh8::build_detail
