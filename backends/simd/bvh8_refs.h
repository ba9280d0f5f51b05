#pragma once
/// The builder's references to primitives (PrimRef: a box and a prim_id), where it reads
/// their corners (CornerSource), and the bounds of a range of them. Internal to the builder
/// (bvh8_*.cpp); the tree's public side is bvh8.h.

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <type_traits>
#include <vector>

#include "backends/simd/bvh8.h"
#include "simd/float4.h"

namespace rp::bvh8::build_detail {

using simd::float4;

/// A primitive's box and its prim_id, 32 bytes: two aligned 16-byte rows, each a box corner in
/// its first three lanes. The SAH splits sort primitives by the box's centre (as Embree's
/// builders do), which gave lower SAH costs on the measured scenes than the triangle's centre
/// of mass (figures: docs/notes/2026-11-29-figures-from-code-comments.md); the lecture notes'
/// median rule sorts by the centre of mass, which it computes (MedianRule). The leaves'
/// corners are gathered straight from the meshes (write_leaves), so a ref need not hold
/// them. Trivial, so that the build's array of them is allocated without a serial zeroing
/// pass and first touched by the parallel loop that fills it.
struct alignas(16) PrimRef {
  float lo[3];
  uint32_t prim_id;
  float hi[3];
  uint32_t pad;
  static PrimRef make(const Box3f& box, uint32_t id) {
    return {{box.lo.x, box.lo.y, box.lo.z}, id, {box.hi.x, box.hi.y, box.hi.z}, 0};
  }
  /// The box's centre on `axis`, as load_center computes it.
  float center(int axis) const { return (lo[axis] + hi[axis]) * 0.5f; }
};
static_assert(sizeof(PrimRef) == 32 && offsetof(PrimRef, hi) == 16);
static_assert(std::is_trivially_default_constructible_v<PrimRef>);

using RefArray = std::vector<PrimRef, HugePageAllocator<PrimRef>>;

/// What a tree holds: the world (every world mesh's triangles and the analytic primitives),
/// or one instanced mesh's triangles.
struct Selection {
  static constexpr uint32_t kWorld = kInvalidId;
  uint32_t mesh = kWorld;
};

/// Where the build reads a primitive's three corners (NaN for an analytic primitive): the
/// scene's meshes (an index and three scattered vertices), or, for spatial splits, which clip
/// triangles many times, a copy made once in prim_id order (one record each). Measured: the
/// copy costs the default build more than its one-pass reads save, and shortens the spatial
/// build (figures: docs/notes/2026-11-29-figures-from-code-comments.md).
class CornerSource {
 public:
  /// `copy`: of the primitives the tree holds, `what` (Selection).
  CornerSource(const Scene& scene, bool copy, const Selection& what);

  std::array<Vec3f, 3> operator()(uint32_t prim) const {
    if (!copy_.empty()) {
      const float* f = copy_[prim - first_].f;
      return {Vec3f{f[0], f[1], f[2]}, Vec3f{f[3], f[4], f[5]}, Vec3f{f[6], f[7], f[8]}};
    }
    if (prim >= scene_.triangle_count()) {
      const Vec3f nan(std::numeric_limits<float>::quiet_NaN());
      return {nan, nan, nan};
    }
    const auto at = scene_.locate(prim);
    const MeshView& m = scene_.meshes()[at.shape];
    return {m.vertex(at.local, 0), m.vertex(at.local, 1), m.vertex(at.local, 2)};
  }

  /// The corners of primitives `ids` into out[3 i .. 3 i + 2]. Primitives in tree order are
  /// scattered over the mesh, so the loop reads ahead: a primitive's index row 16 primitives
  /// before its turn, its corners 8 before, so that many reads are in flight instead of one
  /// (measured faster; figures: docs/notes/2026-11-29-figures-from-code-comments.md). Each
  /// primitive's mesh is looked up once, into a ring of the next 32.
  void gather(std::span<const uint32_t> ids, Vec3f* out) const;

 private:
  /// Where a primitive's corners are: its index row and its mesh's positions; no row for
  /// an analytic primitive (NaN corners).
  struct Triangle {
    const TriangleIndices* row;
    const Strided<Vec3f>* positions;
  };
  Triangle triangle(uint32_t prim) const {
    if (prim >= scene_.triangle_count()) return {nullptr, nullptr};
    const PrimLocation at = scene_.locate(prim);
    const MeshView& m = scene_.meshes()[at.shape];
    return {&m.triangles[at.local], &m.positions};
  }

  struct Record {
    float f[9];
  };
  const Scene& scene_;
  uint32_t first_ = 0;  ///< prim_id of copy_[0]
  std::vector<Record, HugePageAllocator<Record>> copy_;
};

/// A ref's box corners with a zero fourth lane (the prim_id's bits there would be a denormal
/// float, slow in arithmetic), and its box's centre.
inline float4 load_lo(const PrimRef& r) { return simd::load3(r.lo); }
inline float4 load_hi(const PrimRef& r) { return simd::load3(r.hi); }
inline float4 load_center(float4 lo, float4 hi) { return (lo + hi) * simd::splat4(0.5f); }
inline Box3f to_box(float4 lo, float4 hi) {
  alignas(16) float l[4], h[4];
  simd::store4(l, lo);
  simd::store4(h, hi);
  return Box3f({l[0], l[1], l[2]}, {h[0], h[1], h[2]});
}

/// Refs in a range below which its scans (bounds, bins) and a node's two subtrees run in one
/// task.
constexpr uint32_t kParallelThreshold = 4096;

/// The bounds of a range of refs: their boxes, their boxes' centres, and whether any is an
/// analytic primitive.
struct BoxPair {
  Box3f box, centroids;
  bool analytic;
};
/// A node's split: its children are refs[begin, mid) and refs[mid, end), with these
/// bounds; mid == begin: a leaf.
struct Split {
  uint32_t mid;
  BoxPair left, right;
};

/// Bounds of refs[begin, end) and of their centroids, four lanes at a time; in parallel for
/// large ranges (min and max are exact, so the result does not depend on how the range is
/// cut). `first_analytic`: prim_ids from here on are analytic primitives.
BoxPair bounds(const PrimRef* base, uint32_t begin, uint32_t end, uint32_t first_analytic);

/// The split at `mid`, each half's bounds scanned.
Split halves(const PrimRef* base, uint32_t begin, uint32_t end, uint32_t mid, uint32_t first_analytic);

/// Refs for the triangles of mesh m at refs[at + t] (zero-area ones marked kInvalidId, to be
/// dropped); returns how many were zero-area.
size_t triangle_refs(const Scene& scene, size_t m, RefArray& refs, size_t at);

/// Removes the refs marked kInvalidId, keeping the others in order.
void drop_invalid(RefArray& refs);

}  // namespace rp::bvh8::build_detail
