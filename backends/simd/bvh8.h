#pragma once
/// The 8-wide BVH of the simd backend: layout and build. Plain C++ (no SIMD types), so the
/// layout can be inspected and tested anywhere; traversal lives in simd_backend.cpp.

#include <cstdint>
#include <limits>
#include <vector>

#include "engine/bbox.h"
#include "engine/scene.h"

namespace rp::bvh8 {

/// Child reference in a node: >= 0 an inner node index, < 0 the leaf ~child, kEmpty a
/// missing child (its box is empty: lo = +inf, hi = -inf, so no slab test ever hits it).
inline constexpr int32_t kEmpty = std::numeric_limits<int32_t>::min();
inline bool is_leaf(int32_t c) { return c < 0 && c != kEmpty; }

/// Eight child boxes in SoA and the child references. 224 bytes, 32-byte aligned.
struct alignas(32) Bvh8Node {
  float lo_x[8], lo_y[8], lo_z[8];
  float hi_x[8], hi_y[8], hi_z[8];
  int32_t child[8];
};
static_assert(sizeof(Bvh8Node) == 224);

/// A leaf: triangles in slots [tri_first, tri_first + tri_count) of the triangle blocks and
/// other (analytic) primitives others[other_first, other_first + other_count). 16 bytes.
struct Bvh8Leaf {
  uint32_t tri_first = 0, tri_count = 0;
  uint32_t other_first = 0, other_count = 0;
};

/// Eight triangles in SoA, stored for the 8-wide Möller–Trumbore test: v0 and the edges
/// e1 = v1 - v0, e2 = v2 - v0 (computed once, in float, exactly as the scalar routine does),
/// and the scene prim_id of each lane (kInvalidId for padding). 320 bytes: 40 per triangle.
/// Triangle slot s lives in block s / 8, lane s % 8; a leaf's range may straddle two blocks.
struct alignas(32) Tri8 {
  float v0_x[8], v0_y[8], v0_z[8];
  float e1_x[8], e1_y[8], e1_z[8];
  float e2_x[8], e2_y[8], e2_z[8];
  uint32_t prim_id[8];
};
static_assert(sizeof(Tri8) == 320);

enum class SplitRule : uint8_t {
  sah,     ///< binned surface-area heuristic (16 bins per axis), the default
  median,  ///< the seeds' rule: longest axis of the centroids, balanced median split
};

struct BuildOptions {
  SplitRule rule = SplitRule::sah;
  uint32_t max_leaf = 8;  ///< most primitives per leaf (1..8)
};

/// Figures of a built tree.
struct BuildStats {
  uint32_t nodes = 0, leaves = 0, depth = 0;  ///< depth: 8-wide levels, root = 1
  uint32_t prims = 0;                         ///< primitives in the tree (degenerate triangles excluded)
  double sah_cost = 0;   ///< SAH cost of the 8-wide tree: sum of node areas / root area (traversal
                         ///< cost 1) + leaf areas / root area * primitives (intersection cost 1)
  size_t bytes = 0;      ///< nodes + leaves + triangle blocks + other refs
  double seconds = 0;    ///< wall time of build()
};

/// The built tree. Immutable after build().
struct Bvh8 {
  std::vector<Bvh8Node> nodes;  ///< nodes[0] is the root when !empty()
  std::vector<Bvh8Leaf> leaves;
  std::vector<Tri8> tris;
  std::vector<uint32_t> others;  ///< prim_ids of spheres, quadrics, polygons in leaf order
  Box3f bounds;
  BuildStats stats;

  bool empty() const { return nodes.empty(); }
};

/// Builds the tree over every non-degenerate triangle and every sphere, quadric and polygon
/// of `scene` (unbounded planes stay outside it). Parallel (TBB) and deterministic: the same
/// tree, bit for bit, whatever the thread count.
Bvh8 build(const Scene& scene, const BuildOptions& options);

}  // namespace rp::bvh8
