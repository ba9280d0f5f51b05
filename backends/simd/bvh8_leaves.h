#pragma once
/// The leaves' words (see Leaf in bvh8.h): each leaf's vertex block numbered and written, for
/// the leaves the collapse laid out. Internal to the builder (bvh8_*.cpp).

#include <vector>

#include "backends/simd/bvh8.h"
#include "backends/simd/bvh8_collapse.h"
#include "backends/simd/bvh8_refs.h"

namespace rp::bvh8::build_detail {

/// Writes every leaf and points the nodes at them. The leaves are made in chunks of
/// kChunk, in parallel, each chunk into a buffer of its own (its primitives' corners
/// gathered from the meshes, each leaf's vertex block numbered and the leaf written); then
/// the chunks are copied back to back into leaf_data, at offsets from a prefix sum over
/// their sizes, and the nodes' leaf numbers become offsets. A leaf's words depend on the
/// leaf alone and the chunks on the leaf numbering, so the bytes do not depend on the
/// thread count. One pass over the refs and the meshes: no corners kept between passes.
/// `leaves` (from collapse): the leaves of `out`'s nodes, over `refs` (in which, with
/// `repeats`, a primitive may have several refs: spatial splits), their corners read from
/// `corners`.
void write_leaves(const CornerSource& corners, RefArray& refs, bool repeats, std::vector<PlacedLeaf>& leaves,
                  Bvh8& out);

/// For a tree whose leaves each hold one ref (an instance tree): points every leaf child
/// at its ref's id, ~id, instead of at leaf words (there are none).
void point_at_refs(const RefArray& refs, const std::vector<PlacedLeaf>& leaves, Bvh8& out);

}  // namespace rp::bvh8::build_detail
