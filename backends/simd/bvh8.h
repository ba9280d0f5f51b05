#pragma once
/// The 8-wide BVH of the simd backend: layout and build. Plain C++ (no SIMD types), so the
/// layout can be inspected and tested anywhere; the traversal loops are single_ray.h,
/// packet8.h, large_packet.h and stream.h (levels.h).

#include <sys/mman.h>

#include <bit>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <new>
#include <span>
#include <utility>
#include <vector>

#include "base/bbox.h"
#include "core/scene.h"

namespace rp::bvh8 {

/// Child reference in a node: >= 0 an inner node index; < 0 a leaf, ~offset: the leaf
/// starts at leaf_data[offset] (see Leaf); kEmpty a missing child (its box is empty: lo =
/// +inf, hi = -inf, so no slab test ever hits it). `offset` stays at most kMaxLeafOffset, so
/// a leaf never encodes as kEmpty.
inline constexpr int32_t kEmpty = std::numeric_limits<int32_t>::min();
inline constexpr uint32_t kMaxLeafOffset = (1u << 31) - 2;
inline bool is_leaf(int32_t c) { return c < 0 && c != kEmpty; }
inline int32_t leaf_ref(uint32_t offset) { return ~int32_t(offset); }
inline uint32_t leaf_offset(int32_t c) { return uint32_t(~c); }

/// Eight child boxes in SoA and the child references. 224 bytes, 32-byte aligned.
struct alignas(32) Bvh8Node {
  float lo_x[8], lo_y[8], lo_z[8];
  float hi_x[8], hi_y[8], hi_z[8];
  int32_t child[8];
};
static_assert(sizeof(Bvh8Node) == 224);

/// A leaf of n primitives (1..8) with its own vertex block: each distinct vertex of its
/// triangles once, and each corner of a triangle a one-byte index into that block. From the
/// leaf's start (4-byte aligned):
///
/// | bytes               | holds                                                          |
/// |---------------------|----------------------------------------------------------------|
/// | 1                   | n - 1 (bits 0..2) and V - 1 (bits 3..7): V distinct vertices, 1..24 |
/// | 3n, then 0..3 zeros | corner indices: row j (corner j = 0, 1, 2) holds n bytes       |
/// | 4n                  | the scene prim_ids                                             |
/// | 12V                 | the vertices in SoA: x[V], then y[V], then z[V]                |
///
/// On the measured meshes a leaf takes well under the 40 bytes per triangle that v0, the edges
/// and a prim id took (figures: docs/notes/2026-11-29-figures-from-code-comments.md). Vertices
/// are the mesh's floats, bit for bit (equal corners are merged by their bits), so two
/// triangles sharing an edge see the same vertex values in every leaf, as the watertight test
/// needs; Möller–Trumbore's edges are recomputed per test, in float, exactly as the scalar
/// routine computes them. An 8-wide test reads a corner's coordinates as table lookups (one
/// permute per 8 vertices, see simd::lookup), not gathers. An analytic primitive (sphere,
/// quadric, polygon) has a leaf of its own whose one vertex is NaN, which neither triangle test
/// ever hits, and is tested by its scalar routine.
inline constexpr uint32_t kMaxLeafVertices = 24;
inline constexpr uint32_t kLeafPad = 8;  ///< floats after the last leaf: 8-wide loads of its last rows stay in the array

/// Words (floats) of a leaf of n primitives and v distinct vertices.
constexpr uint32_t leaf_words(uint32_t n, uint32_t v) { return (3 * n + 4) / 4 + n + 3 * v; }

/// One leaf as stored (see above), read in place.
struct Leaf {
  const float* words;
  uint32_t n, v;  ///< primitives, distinct vertices

  explicit Leaf(const float* w) : words(w) {
    const uint8_t head = *reinterpret_cast<const uint8_t*>(w);
    n = (head & 7u) + 1;
    v = (head >> 3) + 1;
  }
  /// Row j: the block index of corner j of each primitive (n bytes).
  const uint8_t* corners(uint32_t j) const { return reinterpret_cast<const uint8_t*>(words) + 1 + j * n; }
  uint32_t prim(uint32_t k) const { return std::bit_cast<uint32_t>(words[(3 * n + 4) / 4 + k]); }
  /// x[V], y[V], z[V].
  const float* vertices() const { return words + (3 * n + 4) / 4 + n; }
  /// Corner j (0..2) of primitive k.
  Vec3f vertex(uint32_t k, uint32_t j) const {
    const uint32_t i = corners(j)[k];
    const float* x = vertices();
    return {x[i], x[v + i], x[2 * v + i]};
  }
};

/// Writes at `out` (leaf_words(n, V) floats) the leaf of the n = ids.size() primitives whose
/// corners are corners[3k .. 3k + 2] (an analytic primitive: three NaN corners); returns V.
uint32_t write_leaf(float* out, std::span<const Vec3f> corners, std::span<const uint32_t> ids);

/// Allocator for the tree's arrays (and the build's): 2 MiB-aligned and advised as
/// transparent huge pages (madvise MADV_HUGEPAGE) when large, so random traversal of a big
/// tree misses the TLB far less often and a build takes one page fault per 2 MiB. Small
/// arrays use ordinary aligned allocation. resize() leaves new elements default-initialised
/// (a trivial type's are not written), so no serial zeroing pass precedes the parallel
/// loops that fill the arrays, and each page is first touched by the thread that fills it.
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
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    if constexpr (sizeof...(Args) == 0) ::new (static_cast<void*>(p)) U;
    else ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
  template <typename U>
  bool operator==(const HugePageAllocator<U>&) const { return true; }
};

enum class SplitRule : uint8_t {
  sah,     ///< binned surface-area heuristic (16 bins per axis), the default
  median,  ///< the lecture notes' rule: longest axis of the centroids, balanced median split
};

struct BuildOptions {
  SplitRule rule = SplitRule::sah;
  uint32_t max_leaf = 8;  ///< most primitives per leaf (1..8)
  /// With the SAH rule: spatial splits (SBVH, Stich, Friedrich and Dietrich, "Spatial Splits
  /// in Bounding Volume Hierarchies", HPG 2009). A node whose best object split leaves
  /// overlapping children may instead cut space at a plane, a triangle crossing it going to
  /// both sides with its box clipped there, so a triangle may sit in several leaves (once in
  /// each). Hits do not change: the closest hit is the least (t, prim_id) whatever the tree.
  bool spatial_splits = false;
};

/// Figures of a built tree.
struct BuildStats {
  uint32_t nodes = 0, leaves = 0, depth = 0;  ///< depth: 8-wide levels, root = 1
  uint32_t prims = 0;                         ///< primitives in the tree (degenerate triangles excluded)
  double built_sah_cost = 0;                  ///< sah_cost when the tree was built (refit changes sah_cost only)
  double sah_cost = 0;   ///< SAH cost of the 8-wide tree, the one its collapse minimises: sum over
                         ///< nodes of area / root area (traversal cost 1) + sum over leaves of
                         ///< area / root area * (0.5 per block test + 0.1 per primitive)
  size_t bytes = 0;      ///< nodes + leaves
  double seconds = 0;    ///< wall time of build()
};

/// The built tree. Immutable after build().
struct Bvh8 {
  std::vector<Bvh8Node, HugePageAllocator<Bvh8Node>> nodes;  ///< nodes[0] is the root when !empty()
  /// Every leaf (see Leaf), leaf after leaf in tree order, then kLeafPad zeros.
  std::vector<float, HugePageAllocator<float>> leaf_data;
  std::vector<uint32_t> zero_area;       ///< prim_ids of the triangles left out for zero area (refit)
  uint32_t first_analytic = kInvalidId;  ///< prim_ids >= this in a leaf are analytic
  bool has_analytic = false;             ///< any analytic primitive in the tree
  Box3f bounds;
  BuildStats stats;

  bool empty() const { return nodes.empty(); }
  /// The leaf `ref`.
  Leaf leaf(int32_t ref) const { return Leaf(leaf_data.data() + leaf_offset(ref)); }
  /// prim_id of primitive i of the leaf `ref`.
  uint32_t prim_id(int32_t ref, uint32_t i) const { return leaf(ref).prim(i); }
};

/// Builds the world's tree: every non-degenerate triangle of every world mesh and every
/// sphere, quadric and polygon of `scene` (unbounded planes stay outside it, instanced meshes
/// are in trees of their own). Parallel (TBB) and deterministic: the same tree, bit for bit,
/// whatever the thread count.
Bvh8 build(const Scene& scene, const BuildOptions& options);

/// The side of a cube with the mean surface area of the leaf boxes of `bvh` (0 when empty).
float mean_leaf_size(const Bvh8& bvh);

/// Builds the tree of instanced mesh `mesh` alone, in its object space (its leaves hold the
/// mesh's prim_ids): built once, traversed for every instance that places the mesh.
Bvh8 build_mesh(const Scene& scene, uint32_t mesh, const BuildOptions& options);

/// What refit() did.
enum class Refit : uint8_t {
  done,     ///< the tree holds the new vertices and boxes
  rebuild,  ///< the tree cannot or should not be refitted: build it anew (the tree is unusable)
};

/// Refits `bvh`, the tree that build() (`mesh` = kInvalidId) or build_mesh(scene, mesh, ...)
/// made, to the scene's current vertices, whose triangles are the ones it was built over: each
/// leaf's vertex block rewritten in place, each leaf's box recomputed from its vertices, then
/// the nodes' boxes bottom-up; the topology is kept. In parallel; the result does not depend
/// on the thread count. Returns Refit::rebuild when a refit would be wrong or poor: a triangle
/// that had zero area at the build (and so is in no leaf) has area now; two corners that shared
/// a vertex slot of a leaf (equal bits) now differ; or the SAH cost has grown past `limit`
/// times built_sah_cost.
Refit refit(Bvh8& bvh, const Scene& scene, uint32_t mesh, double limit);

/// Renumbers the primitives of an instanced mesh's tree (build_mesh) whose first prim_id moved
/// from `from` to `to` (meshes before it removed or added): its leaves' ids shifted, nothing else.
void renumber(Bvh8& bvh, uint32_t from, uint32_t to);

/// The top level of a scene with instances: an 8-wide tree (Bvh8Node) over the instances'
/// world boxes, by binned SAH, each instance a leaf of its own whose reference is ~instance
/// (is_leaf, and leaf_offset gives the instance id; there are no leaf words). A box is the
/// instance's (Instance::bounds) grown by 2^-16 of its size and distance from the origin,
/// times the transform's condition number: the rounding of the object-space ray moves a hit
/// point by far less, so no box culls a hit its instance would give for rays that start
/// within about 2^6 times that distance (rays from much farther away may lose a hit within
/// rounding of the box's faces, as the Embree adapter's instances may).
struct InstanceTree {
  std::vector<Bvh8Node, HugePageAllocator<Bvh8Node>> nodes;  ///< nodes[0] is the root when !empty()
  Box3f bounds;
  BuildStats stats;  ///< prims: instances in the tree; no sah_cost

  bool empty() const { return nodes.empty(); }
};

/// Builds the instance tree of `scene` (empty without instances). Deterministic.
InstanceTree build_instances(const Scene& scene);

}  // namespace rp::bvh8
