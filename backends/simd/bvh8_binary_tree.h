#pragma once
/// The binary build tree over the refs, top-down: binned SAH (bvh8_binned_sah.h), with
/// spatial splits (bvh8_spatial.h) when asked, or the median rule (bvh8_median.h); each node
/// planned for the collapse (bvh8_collapse.h) as its children finish. Internal to the builder.

#include <tbb/concurrent_vector.h>
#include <tbb/enumerable_thread_specific.h>

#include <cstddef>
#include <cstdint>

#include "backends/simd/bvh8_build_node.h"
#include "backends/simd/bvh8_median.h"
#include "backends/simd/bvh8_refs.h"

namespace rp::bvh8::build_detail {

/// Builds the binary tree over a tree's refs (build()) and owns its nodes.
class BinaryTreeBuilder {
 public:
  /// `first_analytic`: prim_ids from here on are analytic primitives.
  BinaryTreeBuilder(const CornerSource& corners, RefArray& refs, const BuildOptions& o, uint32_t first_analytic);

  /// The binary tree over every ref; its nodes live as long as the builder. With spatial
  /// splits the refs are replaced by the leaves' refs (pieces of split triangles included),
  /// leaf after leaf in tree order.
  const BuildNode& build();

 private:
  /// The subtree over refs[begin, end), whose bounds are `b`.
  BuildNode* build(uint32_t begin, uint32_t end, uint32_t depth, const BoxPair& b);

  /// The subtree over the refs `v` (bounds `b`) with spatial splits, which may add at most
  /// `budget` refs below this node (the root's budget is the primitive count, so a tree holds
  /// at most twice as many refs as primitives; a split hands what it leaves to its children in
  /// proportion to their refs). Without a budget, triangles that no plane separates (copies
  /// of one triangle) would be duplicated at every level. Its nodes' ranges are set by
  /// place(); until then a node's end - begin is its number of refs, and a leaf's begin is
  /// the index of its refs in leaf_refs_.
  BuildNode* build_spatial(RefArray v, uint32_t depth, const BoxPair& b, size_t budget);

  /// Lays the leaves' refs out in tree order from refs_[at] and sets every node's range;
  /// returns the end of the subtree's.
  uint32_t place(BuildNode& n, uint32_t at);

  const CornerSource& corners_;
  RefArray& refs_;
  const BuildOptions& opt_;
  uint32_t first_analytic_;
  tbb::enumerable_thread_specific<NodeArena> arenas_;
  MedianRule median_;
  float root_area_ = 0.0f;                      ///< spatial splits: the root box's area
  tbb::concurrent_vector<RefArray> leaf_refs_;  ///< spatial splits: each leaf's refs until place()
};

}  // namespace rp::bvh8::build_detail
