#pragma once
/// The 8-wide BVH of the simd backend: layout and build. Plain C++ (no SIMD types), so the
/// layout can be inspected and tested anywhere; traversal lives in simd_backend.cpp.

#include <sys/mman.h>

#include <bit>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <new>
#include <vector>

#include "engine/bbox.h"
#include "engine/scene.h"

namespace rp::bvh8 {

/// Child reference in a node: >= 0 an inner node index; < 0 a leaf, ~(first << 3 |
/// (count - 1)): `count` (1..8) primitives, the tree's primitives [first, first + count) (see
/// Bvh8::leaf); kEmpty a missing child (its box is empty: lo = +inf, hi = -inf, so no slab
/// test ever hits it). `first` stays below 2^28 - 1, so a leaf never encodes as kEmpty.
inline constexpr int32_t kEmpty = std::numeric_limits<int32_t>::min();
inline constexpr uint32_t kMaxPrims = (1u << 28) - 1;
inline bool is_leaf(int32_t c) { return c < 0 && c != kEmpty; }
inline int32_t leaf_ref(uint32_t first, uint32_t count) { return ~int32_t(first << 3 | (count - 1)); }
inline uint32_t leaf_first(int32_t c) { return uint32_t(~c) >> 3; }
inline uint32_t leaf_count(int32_t c) { return (uint32_t(~c) & 7u) + 1; }

/// Eight child boxes in SoA and the child references. 224 bytes, 32-byte aligned.
struct alignas(32) Bvh8Node {
  float lo_x[8], lo_y[8], lo_z[8];
  float hi_x[8], hi_y[8], hi_z[8];
  int32_t child[8];
};
static_assert(sizeof(Bvh8Node) == 224);

/// A leaf of n primitives (1..8) is 10 rows of n values, 40 bytes per primitive and no
/// padding: v0_x, v0_y, v0_z, p1_x, p1_y, p1_z, p2_x, p2_y, p2_z (floats), then the scene
/// prim_ids (uint32 bits). Tri8 spells out the layout for n = 8.
/// What p1 and p2 hold depends on the triangle test the tree is built for (TriangleLayout):
/// - edges (Möller–Trumbore): v0, p1 = e1 = v0 - v1, p2 = e2 = v2 - v0, computed once in
///   float exactly as the scalar rp::intersect_triangle_mt_normal does (the normal e2 x e1 is
///   recomputed per test, which keeps a primitive at 40 bytes);
/// - vertices (watertight): v0, p1 = v1, p2 = v2 as the mesh stores them, because the
///   watertight test needs the very vertex values its neighbours share.
/// An analytic primitive (sphere, quadric, polygon) has NaN coordinates, which neither
/// triangle test ever hits, and is tested by its scalar routine. Leaves are stored back to
/// back in tree order, so a leaf's first primitive also gives its offset (Bvh8::leaf).
inline constexpr uint32_t kLeafRows = 10;
inline constexpr uint32_t kLeafPad = 8;  ///< floats after the last leaf, so 8-wide row loads stay in the array
struct alignas(32) Tri8 {
  float v0_x[8], v0_y[8], v0_z[8];
  float p1_x[8], p1_y[8], p1_z[8];
  float p2_x[8], p2_y[8], p2_z[8];
  uint32_t prim_id[8];
};
static_assert(sizeof(Tri8) == 320);

/// Allocator for the tree's arrays: 2 MiB-aligned and advised as transparent huge pages
/// (madvise MADV_HUGEPAGE) when large, so random traversal of a big tree misses the TLB far
/// less often. Small arrays use ordinary aligned allocation.
template <typename T>
struct HugePageAllocator {
  using value_type = T;
  static constexpr size_t kHuge = size_t(2) << 20;
  HugePageAllocator() = default;
  template <typename U>
  HugePageAllocator(const HugePageAllocator<U>&) {}
  T* allocate(size_t n) {
    const size_t bytes = n * sizeof(T);
    const size_t align = bytes >= kHuge ? kHuge : alignof(T) < 64 ? 64 : alignof(T);
    void* p = std::aligned_alloc(align, (bytes + align - 1) / align * align);
    if (!p) throw std::bad_alloc();
    if (bytes >= kHuge) madvise(p, (bytes + align - 1) / align * align, MADV_HUGEPAGE);
    return static_cast<T*>(p);
  }
  void deallocate(T* p, size_t) { std::free(p); }
  template <typename U>
  bool operator==(const HugePageAllocator<U>&) const { return true; }
};

enum class SplitRule : uint8_t {
  sah,     ///< binned surface-area heuristic (16 bins per axis), the default
  median,  ///< the lecture notes' rule: longest axis of the centroids, balanced median split
};

/// What the leaf blocks store for a triangle (see Tri8).
enum class TriangleLayout : uint8_t { edges, vertices };

struct BuildOptions {
  SplitRule rule = SplitRule::sah;
  uint32_t max_leaf = 8;  ///< most primitives per leaf (1..8)
  TriangleLayout layout = TriangleLayout::edges;
};

/// Figures of a built tree.
struct BuildStats {
  uint32_t nodes = 0, leaves = 0, depth = 0;  ///< depth: 8-wide levels, root = 1
  uint32_t prims = 0;                         ///< primitives in the tree (degenerate triangles excluded)
  double sah_cost = 0;   ///< SAH cost of the 8-wide tree, the one its collapse minimises: sum over
                         ///< nodes of area / root area (traversal cost 1) + sum over leaves of
                         ///< area / root area * (0.5 per block test + 0.1 per primitive)
  size_t bytes = 0;      ///< nodes + leaves
  double seconds = 0;    ///< wall time of build()
};

/// The built tree. Immutable after build().
struct Bvh8 {
  std::vector<Bvh8Node, HugePageAllocator<Bvh8Node>> nodes;  ///< nodes[0] is the root when !empty()
  /// Every leaf's rows (see Tri8), leaf after leaf, then kLeafPad zeros.
  std::vector<float, HugePageAllocator<float>> leaf_data;
  uint32_t first_analytic = kInvalidId;  ///< prim_ids >= this in a leaf are analytic
  bool has_analytic = false;             ///< any analytic primitive in the tree
  Box3f bounds;
  BuildStats stats;

  bool empty() const { return nodes.empty(); }
  /// The rows of the leaf whose first primitive is `first`.
  const float* leaf(uint32_t first) const { return leaf_data.data() + size_t(first) * kLeafRows; }
  /// prim_id of primitive i of the leaf `ref`.
  uint32_t prim_id(int32_t ref, uint32_t i) const {
    return std::bit_cast<uint32_t>(leaf(leaf_first(ref))[9 * leaf_count(ref) + i]);
  }
};

/// Builds the tree over every non-degenerate triangle and every sphere, quadric and polygon
/// of `scene` (unbounded planes stay outside it). Parallel (TBB) and deterministic: the same
/// tree, bit for bit, whatever the thread count.
Bvh8 build(const Scene& scene, const BuildOptions& options);

}  // namespace rp::bvh8
