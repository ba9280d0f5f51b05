#include <tbb/blocked_range.h>
#include <tbb/concurrent_vector.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <cstddef>
#include <limits>
#include <memory>
#include <type_traits>
#include <utility>
#include <vector>

#include "backends/simd/bvh8.h"
#include "engine/error.h"
#include "simd/float4.h"

namespace rp::bvh8 {

namespace {

using simd::float4;
using simd::int4;

/// A primitive's box and its prim_id, 32 bytes: two aligned 16-byte rows, each a box corner in
/// its first three lanes. The SAH splits sort primitives by the box's centre (as Embree's
/// builders do), which gave lower SAH costs on the measured scenes than the triangle's centre
/// of mass (figures: docs/notes/2026-11-29-figures-from-code-comments.md); the lecture notes'
/// median rule sorts by the centre of mass, which it computes (Builder::mass_center). The
/// leaves' corners are gathered straight from the meshes (Collapser::make_chunk), so a ref
/// need not hold them. Trivial, so that the build's array of them is allocated without a
/// serial zeroing pass and first touched by the parallel loop that fills it.
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
  CornerSource(const Scene& scene, bool copy, const Selection& what) : scene_(scene) {
    if (!copy) return;
    const bool world = what.mesh == Selection::kWorld;
    first_ = world ? 0 : scene.mesh_base(what.mesh);
    copy_.resize(world ? scene.plane_base() : scene.meshes()[what.mesh].triangle_count());
    for (size_t m = 0; m < scene.meshes().size(); ++m) {
      if (world ? scene.is_instanced(m) : m != what.mesh) continue;  // not in this tree: never read
      const TriangleMesh& mesh = scene.meshes()[m];
      const uint32_t base = scene.mesh_base(m) - first_;
      tbb::parallel_for(tbb::blocked_range<uint32_t>(0, mesh.triangle_count(), 4096),
                        [&](const tbb::blocked_range<uint32_t>& r) {
                          for (uint32_t t = r.begin(); t < r.end(); ++t) {
                            const Vec3f a = mesh.vertex(t, 0), b = mesh.vertex(t, 1), c = mesh.vertex(t, 2);
                            copy_[base + t] = {a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z};
                          }
                        });
    }
    if (world)
      for (uint32_t id = scene.triangle_count(); id < scene.plane_base(); ++id)
        std::fill_n(copy_[id].f, 9, std::numeric_limits<float>::quiet_NaN());
  }

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
    const TriangleMesh& m = scene_.meshes()[at.shape];
    return {m.vertex(at.local, 0), m.vertex(at.local, 1), m.vertex(at.local, 2)};
  }

  /// The corners of primitives `ids` into out[3 i .. 3 i + 2]. Primitives in tree order are
  /// scattered over the mesh, so the loop reads ahead: a primitive's index row 16 primitives
  /// before its turn, its corners 8 before, so that many reads are in flight instead of one
  /// (measured faster; figures: docs/notes/2026-11-29-figures-from-code-comments.md). Each
  /// primitive's mesh is looked up once, into a ring of the next 32.
  void gather(std::span<const uint32_t> ids, Vec3f* out) const {
    const size_t n = ids.size();
    if (!copy_.empty()) {
      for (size_t i = 0; i < n; ++i) {
        const float* f = copy_[ids[i] - first_].f;
        for (int j = 0; j < 3; ++j) out[3 * i + j] = {f[3 * j], f[3 * j + 1], f[3 * j + 2]};
      }
      return;
    }
    constexpr size_t kIndexAhead = 16, kCornersAhead = 8, kRing = 32;
    Triangle ring[kRing];
    for (size_t i = 0; i < std::min(n, kIndexAhead); ++i) ring[i] = triangle(ids[i]);
    const Vec3f nan(std::numeric_limits<float>::quiet_NaN());
    for (size_t i = 0; i < n; ++i) {
      if (i + kIndexAhead < n) {
        Triangle& t = ring[(i + kIndexAhead) % kRing];
        t = triangle(ids[i + kIndexAhead]);
        if (t.row) simd::prefetch(t.row);
      }
      if (i + kCornersAhead < n) {
        const Triangle& t = ring[(i + kCornersAhead) % kRing];
        if (t.row)
          for (int j = 0; j < 3; ++j) simd::prefetch(t.positions + t.row[j]);
      }
      const Triangle& t = ring[i % kRing];
      for (int j = 0; j < 3; ++j) out[3 * i + j] = t.row ? t.positions[t.row[j]] : nan;
    }
  }

 private:
  /// Where a primitive's corners are: its index row and its mesh's positions; no row for
  /// an analytic primitive (NaN corners).
  struct Triangle {
    const uint32_t* row;
    const Vec3f* positions;
  };
  Triangle triangle(uint32_t prim) const {
    if (prim >= scene_.triangle_count()) return {nullptr, nullptr};
    const PrimLocation at = scene_.locate(prim);
    const TriangleMesh& m = scene_.meshes()[at.shape];
    return {m.indices.data() + 3 * size_t(at.local), m.positions.data()};
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

/// Binary build tree: a leaf has no children and owns refs[begin, end). Each node also carries
/// its row of the cost-optimal collapse into 8-wide nodes (see Builder::plan). Nodes live in
/// a NodeArena.
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
  bool analytic;  ///< holds an analytic primitive (see Builder::may_leaf)
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

constexpr int kBins = 32;  ///< bins per axis for large nodes; small nodes use fewer (bins_for)

/// Bins for a node of n primitives: 32 near the root, where the split matters most, fewer
/// below 560 (Embree's 4 + n / 20, but at least 6), where a sweep over mostly
/// empty bins would cost more than it finds. Against 8 / 16 / 32 bins below 64 / 1024 / above:
/// a slightly faster build at about the same SAH cost (figures:
/// docs/notes/2026-11-29-figures-from-code-comments.md).
constexpr int bins_for(uint32_t n) { return n >= 560 ? kBins : std::max(6, int(4 + n / 20)); }
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
constexpr uint32_t kParallelThreshold = 4096;
constexpr uint32_t kMaxSahDepth = 64;  ///< deeper than this, median splits bound the depth

class Builder {
 public:
  /// `first_analytic`: prim_ids from here on are analytic primitives.
  Builder(const CornerSource& corners, RefArray& refs, const BuildOptions& o, uint32_t first_analytic)
      : corners_(corners), refs_(refs), opt_(o), first_analytic_(first_analytic) {
    if (o.rule != SplitRule::median || refs.empty()) return;
    uint32_t lo = kInvalidId, hi = 0;
    for (const PrimRef& r : refs) {
      lo = std::min(lo, r.prim_id);
      hi = std::max(hi, r.prim_id);
    }
    mass_base_ = lo;
    mass_.resize(size_t(hi - lo) + 1);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, refs.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i < r.end(); ++i) {
        const PrimRef& ref = refs[i];
        Vec3f& c = mass_[ref.prim_id - lo];
        if (ref.prim_id >= first_analytic) {
          c = {ref.center(0), ref.center(1), ref.center(2)};
        } else {
          const std::array<Vec3f, 3> v = corners(ref.prim_id);
          c = (v[0] + v[1] + v[2]) * (1.0f / 3.0f);
        }
      }
    });
  }

  /// The binary tree over every ref; its nodes live as long as the builder. With spatial
  /// splits the refs are replaced by the leaves' refs (pieces of split triangles included),
  /// leaf after leaf in tree order.
  const BuildNode& build() {
    const uint32_t n = uint32_t(refs_.size());
    const BoxPair b = bounds(refs_.data(), 0, n);
    if (!(opt_.spatial_splits && opt_.rule == SplitRule::sah)) return *build(0, n, 0, b);
    root_area_ = b.box.area();
    BuildNode* root = build_spatial(RefArray(refs_), 0, b, n);
    size_t total = 0;
    for (const RefArray& r : leaf_refs_) total += r.size();
    RP_CHECK(total < kInvalidId, "bvh8: ", total, " references after spatial splits");
    refs_.resize(total);
    place(*root, 0);
    return *root;
  }

 private:
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
  /// The cheapest cut of one axis's bins: cut b (1..nbins-1) leaves bins [0, b) on the left
  /// and [b, nbins) on the right; its cost is the sum over both sides of box area times refs,
  /// a ref counted left of every cut after its entry bin and right of every cut up to its
  /// exit bin (the same bin for object splits). sah = inf when no cut has refs on both sides.
  struct Cut {
    float sah = std::numeric_limits<float>::infinity();
    int bin = 0;
    float4 left_lo, left_hi, right_lo, right_hi;
  };
  /// The best cut over three axes of nbins bins each (object or spatial): axis -1 when none.
  struct BinnedSplit {
    Cut cut;
    int axis = -1, nbins = 0;
  };

  /// The subtree over refs[begin, end), whose bounds are `b`.
  BuildNode* build(uint32_t begin, uint32_t end, uint32_t depth, const BoxPair& b) {
    BuildNode* node = arenas_.local().make();
    node->begin = begin;
    node->end = end;
    node->left = node->right = nullptr;
    node->box = b.box;
    node->analytic = b.analytic;
    const uint32_t n = end - begin;
    PrimRef* base = refs_.data();
    Split split{begin, {}, {}};  // stays a leaf
    if (n <= 1) {
    } else if (opt_.rule == SplitRule::sah && depth < kMaxSahDepth) {
      if (!(may_leaf(*node) && n <= kAlwaysLeaf)) {
        const BinnedSplit o = object_split(base, begin, end, b.centroids);
        if (!(may_leaf(*node) && leaf_cheaper(n, o.cut.sah, b.box))) split = apply(base, begin, end, o, b.centroids);
      }
    } else if (!may_leaf(*node)) {
      split = halves(base, begin, end, median_split(base, begin, end, node->box));
    }
    if (const uint32_t mid = split.mid; mid != begin) {
      if (n > kParallelThreshold) {
        tbb::parallel_invoke([&] { node->left = build(begin, mid, depth + 1, split.left); },
                             [&] { node->right = build(mid, end, depth + 1, split.right); });
      } else {
        node->left = build(begin, mid, depth + 1, split.left);
        node->right = build(mid, end, depth + 1, split.right);
      }
    }
    plan(*node);
    return node;
  }

  // ---- spatial splits (BuildOptions::spatial_splits) ----

  /// Overlap of a node's children below which no spatial split is tried, relative to the root's
  /// area (Stich et al.'s alpha): only where object splits leave children overlapping does
  /// cutting space pay for the references it adds. Stich et al. use 1e-5; measured, 1e-3 keeps
  /// nearly all of the SAH gain and the diffuse-ray speed, with a much shorter build and fewer
  /// references (figures: docs/notes/2026-11-29-figures-from-code-comments.md).
  static constexpr float kMinOverlap = 1e-3f;

  /// Position of plane k (0..nbins) of the spatial bins of `box` on `axis`.
  static float plane(const Box3f& box, int axis, int k, int nbins) {
    return box.lo[axis] + box.extent()[axis] * (float(k) / float(nbins));
  }

  /// The parts of the triangle `v` inside `box` on either side of the plane x[axis] = at,
  /// each as a box (empty when there is none): the triangle's corners and the points where its
  /// edges cross the plane (in double, then widened by at least two float ulps), clipped to
  /// `box` and to the side. Conservative: together they cover the triangle's part inside `box`.
  static std::pair<Box3f, Box3f> clip(const std::array<Vec3f, 3>& v, const Box3f& box, int axis, float at) {
    Box3f left, right;
    for (int i = 0; i < 3; ++i) {
      const Vec3f &a = v[i], &b = v[(i + 1) % 3];
      if (a[axis] <= at) left.extend(a);
      if (a[axis] >= at) right.extend(a);
      if ((a[axis] < at && b[axis] > at) || (a[axis] > at && b[axis] < at)) {
        const double t = (double(at) - a[axis]) / (double(b[axis]) - a[axis]);
        Box3f cross;
        for (int c = 0; c < 3; ++c) {
          const float x = float(a[c] + t * (double(b[c]) - a[c]));
          const float e = std::abs(x) * 0x1p-22f + std::numeric_limits<float>::min();  // >= 2 ulps of x
          cross.lo[c] = c == axis ? at : x - e;
          cross.hi[c] = c == axis ? at : x + e;
        }
        left.extend(cross);
        right.extend(cross);
      }
    }
    left.hi[axis] = std::min(left.hi[axis], at);
    right.lo[axis] = std::max(right.lo[axis], at);
    auto inside = [&box](Box3f p) {
      for (int c = 0; c < 3; ++c) {
        p.lo[c] = std::max(p.lo[c], box.lo[c]);
        p.hi[c] = std::min(p.hi[c], box.hi[c]);
      }
      return p;
    };
    return {inside(left), inside(right)};
  }

  static Box3f box_of(const PrimRef& r) { return Box3f({r.lo[0], r.lo[1], r.lo[2]}, {r.hi[0], r.hi[1], r.hi[2]}); }

  /// Area where the two sides of an object split overlap.
  static float overlap(const BinnedSplit& o) {
    const float4 lo = simd::max4(o.cut.left_lo, o.cut.right_lo), hi = simd::min4(o.cut.left_hi, o.cut.right_hi);
    alignas(16) float l[4], h[4];
    simd::store4(l, lo);
    simd::store4(h, hi);
    for (int c = 0; c < 3; ++c)
      if (!(l[c] <= h[c])) return 0.0f;
    return simd::area4(lo, hi);
  }

  /// The best spatial split of the triangle refs `v` under `box`: per axis, bins between
  /// equally spaced planes, each ref entering the bin of its low end and leaving by that of
  /// its high end, its box chopped at every plane in between (Stich et al., sec. 4).
  BinnedSplit spatial_split(const RefArray& v, const Box3f& box) const {
    BinnedSplit best;
    const int nbins = bins_for(uint32_t(v.size()));
    const Vec3f extent = box.extent();
    constexpr float inf = std::numeric_limits<float>::infinity();
    for (int axis = 0; axis < 3; ++axis) {
      if (!(extent[axis] > 0.0f)) continue;
      const float scale = float(nbins) / extent[axis];
      float4 lo[kBins], hi[kBins];
      uint32_t enter[kBins] = {}, leave[kBins] = {};
      std::fill_n(lo, nbins, simd::splat4(inf));
      std::fill_n(hi, nbins, simd::splat4(-inf));
      auto add = [&](int k, const Box3f& b) {
        lo[k] = simd::min4(lo[k], simd::make_float4(b.lo.x, b.lo.y, b.lo.z, 0.0f));
        hi[k] = simd::max4(hi[k], simd::make_float4(b.hi.x, b.hi.y, b.hi.z, 0.0f));
      };
      for (const PrimRef& r : v) {
        const int first = bin_of(r.lo[axis], box.lo[axis], scale, nbins);
        const int last = bin_of(r.hi[axis], box.lo[axis], scale, nbins);
        Box3f piece = box_of(r);
        if (first < last) {
          const std::array<Vec3f, 3> tri = corners_(r.prim_id);
          for (int k = first; k < last; ++k) {
            const auto [l, rest] = clip(tri, piece, axis, plane(box, axis, k + 1, nbins));
            if (!l.empty()) add(k, l);
            piece = rest;
          }
        }
        if (!piece.empty()) add(last, piece);
        ++enter[first];
        ++leave[last];
      }
      const Cut c = sweep(lo, hi, enter, leave, nbins);
      if (c.sah < best.cut.sah) best = {c, axis, nbins};
    }
    return best;
  }

  /// Sends each ref of `v` to the side of the split's plane it lies on, a ref crossing it to
  /// both as its two clipped parts (a part with an empty box is dropped). False when a side
  /// would be empty.
  bool divide(const RefArray& v, const BinnedSplit& s, const Box3f& box, RefArray& left, RefArray& right) const {
    const int axis = s.axis;
    const int cut = s.cut.bin;
    const float scale = float(s.nbins) / box.extent()[axis], at = plane(box, axis, cut, s.nbins);
    for (const PrimRef& r : v) {
      if (bin_of(r.hi[axis], box.lo[axis], scale, s.nbins) < cut) {
        left.push_back(r);
      } else if (bin_of(r.lo[axis], box.lo[axis], scale, s.nbins) >= cut) {
        right.push_back(r);
      } else {
        const auto [l, rr] = clip(corners_(r.prim_id), box_of(r), axis, at);
        if (!l.empty()) left.push_back(PrimRef::make(l, r.prim_id));
        if (!rr.empty()) right.push_back(PrimRef::make(rr, r.prim_id));
      }
    }
    return !left.empty() && !right.empty();
  }

  /// The subtree over the refs `v` (bounds `b`) with spatial splits, which may add at most
  /// `budget` refs below this node (the root's budget is the primitive count, so a tree holds
  /// at most twice as many refs as primitives; a split hands what it leaves to its children in
  /// proportion to their refs). Without a budget, triangles that no plane separates (copies
  /// of one triangle) would be duplicated at every level. Its nodes' ranges are set by
  /// place(); until then a node's end - begin is its number of refs, and a leaf's begin is
  /// the index of its refs in leaf_refs_.
  BuildNode* build_spatial(RefArray v, uint32_t depth, const BoxPair& b, size_t budget) {
    BuildNode* node = arenas_.local().make();
    const uint32_t n = uint32_t(v.size());
    node->begin = 0;
    node->end = n;
    node->left = node->right = nullptr;
    node->box = b.box;
    node->analytic = b.analytic;
    RefArray left, right;
    BoxPair lb, rb;
    if (n > 1 && depth < kMaxSahDepth) {
      PrimRef* base = v.data();
      const BinnedSplit o = object_split(base, 0, n, b.centroids);
      BinnedSplit sp;
      if (budget > 0 && !b.analytic && overlap(o) > kMinOverlap * root_area_) sp = spatial_split(v, b.box);
      if (!(may_leaf(*node) && leaf_cheaper(n, std::min(o.cut.sah, sp.cut.sah), b.box))) {
        if (sp.cut.sah < o.cut.sah && divide(v, sp, b.box, left, right) &&
            left.size() + right.size() - n <= budget) {
          lb = bounds(left.data(), 0, uint32_t(left.size()));
          rb = bounds(right.data(), 0, uint32_t(right.size()));
        } else {
          left.clear();
          right.clear();
          const Split s = apply(base, 0, n, o, b.centroids);
          left.assign(v.begin(), v.begin() + s.mid);
          right.assign(v.begin() + s.mid, v.end());
          lb = s.left;
          rb = s.right;
        }
      }
    } else if (n > 1 && !may_leaf(*node)) {
      const Split s = halves(v.data(), 0, n, median_split(v.data(), 0, n, b.box));
      left.assign(v.begin(), v.begin() + s.mid);
      right.assign(v.begin() + s.mid, v.end());
      lb = s.left;
      rb = s.right;
    }
    if (left.empty()) {
      const auto at = leaf_refs_.push_back(std::move(v));
      node->begin = uint32_t(at - leaf_refs_.begin());
      node->end = node->begin + n;
    } else {
      v = RefArray();
      const size_t nl = left.size(), nr = right.size(), rest = budget - (nl + nr - n);
      const size_t bl = size_t(double(rest) * double(nl) / double(nl + nr)), br = rest - bl;
      if (n > kParallelThreshold) {
        tbb::parallel_invoke([&] { node->left = build_spatial(std::move(left), depth + 1, lb, bl); },
                             [&] { node->right = build_spatial(std::move(right), depth + 1, rb, br); });
      } else {
        node->left = build_spatial(std::move(left), depth + 1, lb, bl);
        node->right = build_spatial(std::move(right), depth + 1, rb, br);
      }
    }
    plan(*node);
    return node;
  }

  /// Lays the leaves' refs out in tree order from refs_[at] and sets every node's range;
  /// returns the end of the subtree's.
  uint32_t place(BuildNode& n, uint32_t at) {
    if (n.leaf()) {
      const RefArray& r = leaf_refs_[n.begin];
      std::copy(r.begin(), r.end(), refs_.begin() + at);
      n.begin = at;
      n.end = at + uint32_t(r.size());
      return n.end;
    }
    n.begin = at;
    n.end = place(*n.right, place(*n.left, at));
    return n.end;
  }

  /// Bounds of refs[begin, end) and of their centroids, four lanes at a time; in parallel for
  /// large ranges (min and max are exact, so the result does not depend on how the range is
  /// cut).
  struct Bounds {
    float4 lo = simd::splat4(std::numeric_limits<float>::infinity());
    float4 hi = simd::splat4(-std::numeric_limits<float>::infinity());
    float4 clo = lo, chi = hi;
    uint32_t analytic = 0;
    void add(const PrimRef& p, uint32_t first_analytic) {
      const float4 l = load_lo(p), h = load_hi(p), c = load_center(l, h);
      lo = simd::min4(lo, l);
      hi = simd::max4(hi, h);
      clo = simd::min4(clo, c);
      chi = simd::max4(chi, c);
      analytic += p.prim_id >= first_analytic;
    }
    BoxPair boxes() const { return {to_box(lo, hi), to_box(clo, chi), analytic != 0}; }
    void join(const Bounds& o) {
      lo = simd::min4(lo, o.lo);
      hi = simd::max4(hi, o.hi);
      clo = simd::min4(clo, o.clo);
      chi = simd::max4(chi, o.chi);
      analytic += o.analytic;
    }
  };
  BoxPair bounds(const PrimRef* base, uint32_t begin, uint32_t end) const {
    auto scan = [&](const tbb::blocked_range<uint32_t>& r, Bounds b) {
      for (uint32_t i = r.begin(); i < r.end(); ++i) b.add(base[i], first_analytic_);
      return b;
    };
    const Bounds b = end - begin < kParallelThreshold
                         ? scan({begin, end}, Bounds{})
                         : tbb::parallel_reduce(tbb::blocked_range<uint32_t>(begin, end, kParallelThreshold), Bounds{}, scan,
                                                [](Bounds a, const Bounds& o) { a.join(o); return a; });
    return b.boxes();
  }

  /// The split at `mid`, each half's bounds scanned.
  Split halves(const PrimRef* base, uint32_t begin, uint32_t end, uint32_t mid) const {
    return {mid, bounds(base, begin, mid), bounds(base, mid, end)};
  }

  /// A node's bin mapping on the three axes at once: lane a of (*this)(centre) is a ref's bin
  /// on axis a, clamp(int((centre - lo) * nbins / extent), 0, nbins - 1), the one rule of
  /// the binning and the partition (0 on an axis of zero extent).
  struct BinMap {
    float4 origin, scale;
    int4 top;
    BinMap(const Box3f& centroids, int nbins) {
      const Vec3f extent = centroids.extent();
      const float nb = float(nbins);
      origin = simd::make_float4(centroids.lo.x, centroids.lo.y, centroids.lo.z, 0.0f);
      scale = simd::make_float4(extent.x > 0.0f ? nb / extent.x : 0.0f, extent.y > 0.0f ? nb / extent.y : 0.0f,
                                extent.z > 0.0f ? nb / extent.z : 0.0f, 0.0f);
      top = simd::splat4(nbins - 1);
    }
    int4 operator()(float4 center) const {
      return simd::min4(simd::max4(simd::truncate4((center - origin) * scale), simd::splat4(0)), top);
    }
  };

  /// Moves the refs whose bin on the split's axis lies below its cut before the others and
  /// returns the split: each side's box is the cut's, each side's centroid bounds and
  /// analytic flag are gathered on the way (no second scan). Lomuto's scheme with the swap
  /// made whether or not the ref goes left, so which side a ref takes is data, not a branch:
  /// the two-pointer scheme this replaced guessed wrong about once per ref, and the guesses
  /// were a large part of its time (figures: docs/notes/2026-11-29-figures-from-code-comments.md).
  Split partition(PrimRef* base, uint32_t begin, uint32_t end, const BinnedSplit& o, const BinMap& map) const {
    const float4 inf = simd::splat4(std::numeric_limits<float>::infinity());
    const float4 ninf = simd::splat4(-std::numeric_limits<float>::infinity());
    float4 left_lo = inf, left_hi = ninf, right_lo = inf, right_hi = ninf;
    uint32_t left_analytic = 0, right_analytic = 0;
    PrimRef* j = base + begin;
    for (PrimRef* i = base + begin; i != base + end; ++i) {
      const PrimRef x = *i;
      const float4 c = load_center(load_lo(x), load_hi(x));
      alignas(16) int32_t k[4];
      simd::store4(k, map(c));
      const bool left = k[o.axis] < o.cut.bin;
      *i = *j;  // [base + begin, j) went left, [j, i) right
      *j = x;
      j += left;
      const float4 m = simd::mask4(left);
      left_lo = simd::min4(left_lo, simd::select4(m, c, inf));
      left_hi = simd::max4(left_hi, simd::select4(m, c, ninf));
      right_lo = simd::min4(right_lo, simd::select4(m, inf, c));
      right_hi = simd::max4(right_hi, simd::select4(m, ninf, c));
      const uint32_t analytic = x.prim_id >= first_analytic_;
      left_analytic += analytic & left;
      right_analytic += analytic & !left;
    }
    return {uint32_t(j - base),
            {to_box(o.cut.left_lo, o.cut.left_hi), to_box(left_lo, left_hi), left_analytic != 0},
            {to_box(o.cut.right_lo, o.cut.right_hi), to_box(right_lo, right_hi), right_analytic != 0}};
  }

  /// Bin boxes and counts for all three axes in one pass over the refs: the three bin indices
  /// of a centroid in one 4-wide step, each bin box a 4-wide min/max (in parallel for large
  /// ranges; unions and integer sums are exact, so the bins do not depend on the cut either).
  struct Bins {
    float4 lo[3][kBins], hi[3][kBins];
    uint32_t count[3][kBins];
    int nbins;
    explicit Bins(int n) : nbins(n) {
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < n; ++b) {
          lo[a][b] = simd::splat4(std::numeric_limits<float>::infinity());
          hi[a][b] = simd::splat4(-std::numeric_limits<float>::infinity());
          count[a][b] = 0;
        }
    }
    void join(const Bins& o) {
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < nbins; ++b) {
          lo[a][b] = simd::min4(lo[a][b], o.lo[a][b]);
          hi[a][b] = simd::max4(hi[a][b], o.hi[a][b]);
          count[a][b] += o.count[a][b];
        }
    }
  };
  /// Fills `out` (constructed for nbins): a return by value would copy its 3.5 KB per node.
  void bin(const PrimRef* base, uint32_t begin, uint32_t end, const BinMap& map, Bins& out) const {
    auto scan_into = [&](const tbb::blocked_range<uint32_t>& r, Bins& b) {
      for (uint32_t i = r.begin(); i < r.end(); ++i) {
        const PrimRef& p = base[i];
        const float4 lo = load_lo(p), hi = load_hi(p);
        alignas(16) int32_t k[4];
        simd::store4(k, map(load_center(lo, hi)));
        for (int a = 0; a < 3; ++a) {
          b.lo[a][k[a]] = simd::min4(b.lo[a][k[a]], lo);
          b.hi[a][k[a]] = simd::max4(b.hi[a][k[a]], hi);
          ++b.count[a][k[a]];
        }
      }
    };
    if (end - begin < kParallelThreshold) {  // most nodes: no copies of the bins
      scan_into({begin, end}, out);
      return;
    }
    auto scan = [&](const tbb::blocked_range<uint32_t>& r, Bins b) {
      scan_into(r, b);
      return b;
    };
    out = tbb::parallel_reduce(tbb::blocked_range<uint32_t>(begin, end, kParallelThreshold), Bins(out.nbins), scan,
                               [](Bins a, const Bins& b) { a.join(b); return a; });
  }

  /// The cheapest cut of one axis's bins (see Cut).
  static Cut sweep(const float4* lo, const float4* hi, const uint32_t* enter, const uint32_t* leave, int nbins) {
    constexpr float inf = std::numeric_limits<float>::infinity();
    float4 right_lo[kBins], right_hi[kBins];
    float right_area[kBins];
    uint32_t right_count[kBins];
    float4 l = simd::splat4(inf), h = simd::splat4(-inf);
    uint32_t count = 0;
    for (int b = nbins - 1; b > 0; --b) {  // a box with no refs yet is never priced (count 0)
      right_lo[b] = l = simd::min4(l, lo[b]);
      right_hi[b] = h = simd::max4(h, hi[b]);
      count += leave[b];
      right_area[b] = simd::area4(l, h);
      right_count[b] = count;
    }
    l = simd::splat4(inf);
    h = simd::splat4(-inf);
    count = 0;
    Cut best;
    for (int b = 1; b < nbins; ++b) {
      l = simd::min4(l, lo[b - 1]);
      h = simd::max4(h, hi[b - 1]);
      count += enter[b - 1];
      if (count == 0 || right_count[b] == 0) continue;
      const float cost = simd::area4(l, h) * float(count) + right_area[b] * float(right_count[b]);
      if (cost < best.sah) best = {cost, b, l, h, right_lo[b], right_hi[b]};
    }
    return best;
  }

  /// Binned SAH (Wald, "On fast Construction of SAH-based Bounding Volume Hierarchies", 2007):
  /// 8-32 bins per axis over the centroid bounds.
  BinnedSplit object_split(const PrimRef* base, uint32_t begin, uint32_t end, const Box3f& centroids) const {
    const Vec3f extent = centroids.extent();
    BinnedSplit best;
    const int nbins = bins_for(end - begin);
    Bins bins(nbins);
    bin(base, begin, end, BinMap(centroids, nbins), bins);
    for (int axis = 0; axis < 3; ++axis) {
      if (!(extent[axis] > 0.0f)) continue;
      const Cut c = sweep(bins.lo[axis], bins.hi[axis], bins.count[axis], bins.count[axis], nbins);
      if (c.sah < best.cut.sah) best = {c, axis, nbins};
    }
    return best;
  }

  /// Whether a leaf of n refs costs no more than a split of this SAH sum under `box`.
  static bool leaf_cheaper(uint32_t n, float sah, const Box3f& box) {
    const float area = box.area();
    const float split_cost = area > 0.0f ? kTraversalCost + kIntersectionCost * sah / area
                                         : std::numeric_limits<float>::infinity();
    return kIntersectionCost * float(n) <= split_cost;
  }

  /// Moves refs[begin, end) to the sides of `o` (or halves them where it has no cut, or where
  /// it would leave a side empty).
  Split apply(PrimRef* base, uint32_t begin, uint32_t end, const BinnedSplit& o, const Box3f& centroids) const {
    if (o.axis < 0) return halves(base, begin, end, object_median(begin, end));  // every centroid coincides
    const Split s = partition(base, begin, end, o, BinMap(centroids, o.nbins));
    return (s.mid == begin || s.mid == end) ? halves(base, begin, end, object_median(begin, end)) : s;
  }

  /// The lecture notes' rule: split the longest axis of the node's box at the median centre of
  /// mass, so both halves hold the same number of primitives.
  uint32_t median_split(PrimRef* base, uint32_t begin, uint32_t end, const Box3f& box) const {
    const int axis = max_abs_axis(box.extent());
    const uint32_t mid = begin + (end - begin) / 2;
    std::nth_element(base + begin, base + mid, base + end, [&](const PrimRef& a, const PrimRef& b) {
      const float ca = mass_center(a, axis), cb = mass_center(b, axis);
      return ca < cb || (ca == cb && a.prim_id < b.prim_id);
    });
    return mid;
  }

  /// A triangle's centre of mass (the lecture notes' "center of mass"), an analytic
  /// primitive's box centre, on `axis`: from mass_ with the median rule, else (the SAH
  /// build's median splits past kMaxSahDepth, rare) from the corners.
  float mass_center(const PrimRef& r, int axis) const {
    if (!mass_.empty()) return mass_[r.prim_id - mass_base_][axis];
    if (r.prim_id >= first_analytic_) return r.center(axis);
    const std::array<Vec3f, 3> v = corners_(r.prim_id);
    return ((v[0] + v[1] + v[2]) * (1.0f / 3.0f))[axis];
  }

  static uint32_t object_median(uint32_t begin, uint32_t end) { return begin + (end - begin) / 2; }

  static int bin_of(float c, float lo, float scale, int nbins) {
    return std::clamp(int((c - lo) * scale), 0, nbins - 1);
  }

  /// The node's row of the cost-optimal collapse (Ylitie, Karras and Laine, "Efficient
  /// Incoherent Ray Traversal on GPUs Through Compressed Wide BVHs", HPG 2017, sec. 4.1),
  /// from its children's rows: the binary tree is cut into 8-wide nodes and leaves so that
  /// the SAH cost is least, where an 8-wide node costs kTraversalCost times its area and a
  /// leaf, one block test, (kLeafCost + kPrimCost * primitives) times its area. A subtree of
  /// at most max_leaf primitives may become one leaf (its refs are contiguous), so small
  /// sibling leaves merge into one block test, and nodes are filled by cost rather than
  /// opened greedily. Runs in the (parallel) build as children finish; the result depends on
  /// the tree only, so it stays deterministic.
  void plan(BuildNode& n) const {
    constexpr float inf = std::numeric_limits<float>::infinity();
    const float area = n.box.area();
    const float leaf = may_leaf(n) ? area * (kLeafCost + kPrimCost * float(n.count())) : inf;
    std::fill_n(n.split, 8, uint8_t(0));
    if (n.leaf()) {
      n.as_leaf = true;
      std::fill_n(n.cost, 8, leaf);
      return;
    }
    const BuildNode &l = *n.left, &r = *n.right;
    float dist[9];  // dist[j]: the subtree as j children (j = 2..8), at[j] of them from the left
    uint8_t at[9] = {};
    for (int j = 2; j <= 8; ++j) {
      dist[j] = inf;
      for (int k = 1; k < j; ++k) {
        const float c = l.cost[k - 1] + r.cost[j - k - 1];
        if (c < dist[j]) {
          dist[j] = c;
          at[j] = uint8_t(k);
        }
      }
    }
    int width = 2;
    for (int j = 3; j <= 8; ++j)
      if (dist[j] < dist[width]) width = j;
    const float inner = area * kTraversalCost + dist[width];
    n.node_width = uint8_t(width);
    n.node_split = at[width];
    n.as_leaf = leaf <= inner;
    n.cost[0] = std::min(leaf, inner);
    for (int i = 2; i <= 8; ++i) {
      if (dist[i] < n.cost[i - 2]) {
        n.cost[i - 1] = dist[i];
        n.split[i - 1] = at[i];
      } else {
        n.cost[i - 1] = n.cost[i - 2];
      }
    }
  }

  /// Whether the subtree may be one leaf: at most max_leaf primitives, and an analytic
  /// primitive only alone. A leaf's box is the only cull before a primitive's test, and a
  /// quadric sharing a leaf with triangles would be tested by every ray that reaches them
  /// (on the default scene, measured, several times as many scalar analytic tests as Embree,
  /// whose user geometry has a box per primitive).
  bool may_leaf(const BuildNode& n) const { return n.count() <= opt_.max_leaf && (n.count() == 1 || !n.analytic); }

  const CornerSource& corners_;
  RefArray& refs_;
  const BuildOptions& opt_;
  uint32_t first_analytic_;
  tbb::enumerable_thread_specific<NodeArena> arenas_;
  std::vector<Vec3f> mass_;                     ///< median rule: mass_center by prim_id - mass_base_
  uint32_t mass_base_ = 0;
  float root_area_ = 0.0f;                      ///< spatial splits: the root box's area
  tbb::concurrent_vector<RefArray> leaf_refs_;  ///< spatial splits: each leaf's refs until place()
};

/// The vertex block of a leaf: each distinct corner (by its bits, NaN included) numbered in
/// first-seen order; `of[c]` is corner c's number, `v` how many there are.
struct CornerIndex {
  uint32_t v = 0;
  uint8_t of[3 * 8];
};

/// Finds each corner's vertex through a 32-slot hash table of the vertices seen so far (a
/// leaf has at most 24), probing on from the hashed slot past occupied slots whose vertex
/// differs. A match and a new vertex then take the same instructions: the linear search
/// this replaced branched on where its match lay, a guess that failed about once per
/// corner (measured slower; figures: docs/notes/2026-11-29-figures-from-code-comments.md).
CornerIndex index_corners(std::span<const Vec3f> corners) {
  constexpr uint32_t kSlots = 32, kFree = 0xff;
  static_assert(kSlots > kMaxLeafVertices);
  CornerIndex ci;
  uint32_t bits[3 * 8][3];  // each corner's coordinates as integers
  uint32_t first[3 * 8];    // first[i]: the corner that vertex i was first seen as
  uint8_t slot_of[kSlots];
  std::memcpy(bits, corners.data(), corners.size() * sizeof(Vec3f));
  std::memset(slot_of, kFree, sizeof(slot_of));
  for (size_t c = 0; c < corners.size(); ++c) {
    const uint32_t* k = bits[c];
    uint32_t slot = ((k[0] * 0x9E3779B1u) ^ (k[1] * 0x85EBCA77u) ^ (k[2] * 0xC2B2AE3Du)) >> 27;
    for (;;) {
      const uint32_t i = slot_of[slot];
      if (i == kFree) break;
      const uint32_t* o = bits[first[i]];
      if (((k[0] ^ o[0]) | (k[1] ^ o[1]) | (k[2] ^ o[2])) == 0) break;
      slot = (slot + 1) % kSlots;
    }
    const bool seen = slot_of[slot] != kFree;
    const uint32_t i = seen ? slot_of[slot] : ci.v;
    first[ci.v] = uint32_t(c);  // kept only when the vertex is new
    ci.v += !seen;
    slot_of[slot] = uint8_t(i);
    ci.of[c] = uint8_t(i);
  }
  return ci;
}

/// Writes the leaf of the primitives `ids` with these corners and their index (see Leaf):
/// leaf_words(n, index.v) floats at `out`.
void store_leaf(float* out, std::span<const Vec3f> corners, std::span<const uint32_t> ids, const CornerIndex& index) {
  const uint32_t n = uint32_t(ids.size()), v = index.v;
  std::fill_n(out, leaf_words(n, v), 0.0f);
  uint8_t* bytes = reinterpret_cast<uint8_t*>(out);
  bytes[0] = uint8_t((n - 1) | (v - 1) << 3);
  for (uint32_t k = 0; k < n; ++k)
    for (uint32_t j = 0; j < 3; ++j) bytes[1 + j * n + k] = index.of[3 * k + j];
  const uint32_t ids_at = (3 * n + 4) / 4;
  for (uint32_t k = 0; k < n; ++k) out[ids_at + k] = std::bit_cast<float>(ids[k]);
  float* x = out + ids_at + n;
  for (size_t c = 0; c < corners.size(); ++c) {  // a shared vertex is written once per corner, the same bits
    const uint32_t i = index.of[c];
    x[i] = corners[c].x;
    x[v + i] = corners[c].y;
    x[2 * v + i] = corners[c].z;
  }
}

/// Lays the binary tree out as 8-wide nodes and leaves, cut as Builder::plan chose
/// (depth-first, single-threaded, so the layout is deterministic).
class Collapser {
 public:
  /// `repeats`: a primitive may have several refs (spatial splits).
  Collapser(const CornerSource& corners, RefArray& refs, Bvh8& out, bool repeats)
      : corners_(corners), refs_(refs), out_(out), repeats_(repeats) {}

  /// Lays the tree out: the nodes over subtrees of at least kSubtree refs in one thread, then
  /// those subtrees in parallel, each at the places its counts give (counted in parallel
  /// too), so the layout is the same whatever the thread count. The binary tree's nodes
  /// are read once more per subtree (to count), but by all threads: walking them is a chain
  /// of cache misses.
  void root(const BuildNode& bn) {
    out_.nodes.resize(1);
    clear(out_.nodes[0]);
    if (bn.as_leaf) {  // a one-leaf tree still needs a root node
      leaves_.resize(1);
      set_child(0, 0, bn, place_leaf(bn, 0));
      out_.stats.depth = 1;
      out_.stats.leaves = 1;
      return;
    }
    std::vector<Subtree> subtrees;
    Cursor top{1, 0, 0};
    lay_out(0, bn, 1, top, &subtrees);
    out_.nodes.resize(top.node);
    leaves_.resize(top.leaf);
    tbb::parallel_for(size_t(0), subtrees.size(), [&](size_t i) { subtrees[i].size = count(*subtrees[i].bn); });
    Cursor next = top;
    for (Subtree& t : subtrees) {
      t.at = {next.node, next.leaf, 0};
      next.node += t.size.nodes;
      next.leaf += t.size.leaves;
    }
    RP_CHECK(next.leaf <= kMaxLeafOffset, "bvh8: more than ", kMaxLeafOffset, " leaves");
    out_.nodes.resize(next.node);
    leaves_.resize(next.leaf);
    tbb::parallel_for(size_t(0), subtrees.size(), [&](size_t i) {
      Subtree& t = subtrees[i];
      const size_t index = t.at.node++;
      clear(out_.nodes[index]);
      set_child(t.parent, t.slot, *t.bn, int32_t(index));
      lay_out(index, *t.bn, t.depth, t.at, nullptr);
    });
    uint32_t depth = top.depth;
    for (const Subtree& t : subtrees) depth = std::max(depth, t.at.depth);
    out_.stats.depth = depth;
    out_.stats.leaves = uint32_t(next.leaf);
  }

 private:
  /// Subtrees of fewer refs are laid out by one task each.
  static constexpr uint32_t kSubtree = 4096;

  /// The next free node and leaf numbers, and the deepest level laid out.
  struct Cursor {
    size_t node, leaf;
    uint32_t depth;
  };
  /// 8-wide nodes and leaves of the layout of an inner `bn` (itself included).
  struct Counts {
    size_t nodes = 0, leaves = 0;
  };
  /// An inner child left by the top of the layout: where its node goes (parent, slot), its
  /// level, size and, once counted, its places.
  struct Subtree {
    size_t parent;
    int slot;
    const BuildNode* bn;
    uint32_t depth;
    Counts size;
    Cursor at;
  };

  static void clear(Bvh8Node& n) {
    constexpr float inf = std::numeric_limits<float>::infinity();
    for (int i = 0; i < 8; ++i) {
      n.lo_x[i] = n.lo_y[i] = n.lo_z[i] = inf;
      n.hi_x[i] = n.hi_y[i] = n.hi_z[i] = -inf;
      n.child[i] = kEmpty;
    }
  }

  void set_child(size_t node, int slot, const BuildNode& c, int32_t ref) {
    Bvh8Node& n = out_.nodes[node];
    n.lo_x[slot] = c.box.lo.x; n.lo_y[slot] = c.box.lo.y; n.lo_z[slot] = c.box.lo.z;
    n.hi_x[slot] = c.box.hi.x; n.hi_y[slot] = c.box.hi.y; n.hi_z[slot] = c.box.hi.z;
    n.child[slot] = ref;
  }

  /// Appends the pieces of `bn` at out[size] when its subtree takes at most i children of a
  /// node.
  static void gather(const BuildNode& bn, int i, const BuildNode** out, int& size) {
    while (i > 1 && bn.split[i - 1] == 0) --i;
    if (i == 1) {
      out[size++] = &bn;
      return;
    }
    gather(*bn.left, bn.split[i - 1], out, size);
    gather(*bn.right, i - bn.split[i - 1], out, size);
  }
  /// The children of the 8-wide node an inner `bn` becomes; returns how many (2..8).
  static int children(const BuildNode& bn, const BuildNode** kids) {
    int size = 0;
    gather(*bn.left, bn.node_split, kids, size);
    gather(*bn.right, bn.node_width - bn.node_split, kids, size);
    return size;
  }

  /// Counts of the layout of an inner `bn`.
  static Counts count(const BuildNode& bn) {
    const BuildNode* kids[8];
    const int size = children(bn, kids);
    Counts c{1, 0};
    for (int k = 0; k < size; ++k) {
      if (kids[k]->as_leaf) {
        ++c.leaves;
      } else {
        const Counts below = count(*kids[k]);
        c.nodes += below.nodes;
        c.leaves += below.leaves;
      }
    }
    return c;
  }

  /// Fills node `index` with the children of an inner `bn` (as_leaf false), as the plan cut
  /// them, then descends, taking node and leaf numbers from `at`. A node's leaves are
  /// numbered one after another, and its inner children's nodes are placed together (as
  /// Embree allocates a node's children): what one ray visits next is often adjacent in
  /// memory. With `defer` (the top of the layout) the arrays grow as it goes, and an inner
  /// child of fewer than kSubtree refs is left to `defer` instead of descended into.
  void lay_out(size_t index, const BuildNode& bn, uint32_t depth, Cursor& at, std::vector<Subtree>* defer) {
    at.depth = std::max(at.depth, depth);
    const BuildNode* kids[8];
    const int size = children(bn, kids);
    if (defer) leaves_.resize(at.leaf + size_t(size));
    int inner[8], inners = 0;
    for (int c = 0; c < size; ++c) {
      if (kids[c]->as_leaf) {
        set_child(index, c, *kids[c], place_leaf(*kids[c], at.leaf++));
      } else if (defer && kids[c]->count() < kSubtree) {
        defer->push_back({index, c, kids[c], depth + 1, {}, {}});
      } else {
        inner[inners++] = c;
      }
    }
    const size_t first = at.node;
    at.node += size_t(inners);
    if (defer) out_.nodes.resize(at.node);
    for (int i = 0; i < inners; ++i) {
      clear(out_.nodes[first + i]);
      set_child(index, inner[i], *kids[inner[i]], int32_t(first + i));
    }
    for (int i = 0; i < inners; ++i) lay_out(first + i, *kids[inner[i]], depth + 1, at, defer);
  }

  /// Records leaf number `index`; its place in leaf_data is known once every leaf's size is
  /// (fill), so until then the node holds the leaf's number where its offset will go.
  int32_t place_leaf(const BuildNode& bn, size_t index) {
    leaves_[index] = {bn.begin, bn.end - bn.begin, 0};
    return leaf_ref(uint32_t(index));
  }

 public:
  /// Writes every leaf and points the nodes at them. The leaves are made in chunks of
  /// kChunk, in parallel, each chunk into a buffer of its own (its primitives' corners
  /// gathered from the meshes, each leaf's vertex block numbered and the leaf written); then
  /// the chunks are copied back to back into leaf_data, at offsets from a prefix sum over
  /// their sizes, and the nodes' leaf numbers become offsets. A leaf's words depend on the
  /// leaf alone and the chunks on the leaf numbering, so the bytes do not depend on the
  /// thread count. One pass over the refs and the meshes: no corners kept between passes.
  void fill() {
    const size_t leaves = leaves_.size(), chunks = (leaves + kChunk - 1) / kChunk;
    std::vector<std::vector<float>> made(chunks);
    tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
      made[c] = make_chunk(c * kChunk, std::min(leaves, (c + 1) * kChunk));
    });
    std::vector<size_t> base(chunks + 1, 0);
    for (size_t c = 0; c < chunks; ++c) base[c + 1] = base[c] + made[c].size();
    RP_CHECK(base[chunks] <= kMaxLeafOffset, "bvh8: the leaves need more than ", uint64_t(kMaxLeafOffset) * 4,
             " bytes");
    out_.leaf_data.resize(base[chunks] + kLeafPad);
    std::fill_n(out_.leaf_data.end() - kLeafPad, kLeafPad, 0.0f);
    tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
      std::copy(made[c].begin(), made[c].end(), out_.leaf_data.begin() + ptrdiff_t(base[c]));
      for (size_t i = c * kChunk; i < std::min(leaves, (c + 1) * kChunk); ++i) leaves_[i].offset += uint32_t(base[c]);
      std::vector<float>().swap(made[c]);
    });
    tbb::parallel_for(tbb::blocked_range<size_t>(0, out_.nodes.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i < r.end(); ++i)
        for (int32_t& c : out_.nodes[i].child)
          if (is_leaf(c)) c = leaf_ref(leaves_[leaf_offset(c)].offset);
    });
  }

  /// For a tree whose leaves each hold one ref (an instance tree): points every leaf child
  /// at its ref's id, ~id, instead of at leaf words (there are none).
  void point_at_refs() {
    for (Bvh8Node& n : out_.nodes)
      for (int32_t& c : n.child)
        if (is_leaf(c)) {
          const Placed& leaf = leaves_[leaf_offset(c)];
          RP_CHECK(leaf.count == 1, "bvh8: an instance leaf of ", leaf.count, " refs");
          c = leaf_ref(refs_[leaf.ref].prim_id);
        }
  }

 private:
  /// Leaves made by one task (fill): about 17 KB of leaf words, whose corners (37 KB)
  /// stay in L1 and L2 between the gather and the writes.
  static constexpr size_t kChunk = 128;

  /// A leaf: its primitives refs_[ref, ref + count) and its offset in leaf_data (in its
  /// chunk's buffer until fill copies it).
  struct Placed {
    uint32_t ref, count, offset;
  };

  /// The words of leaves [first, last) back to back; each leaf's offset among them set.
  std::vector<float> make_chunk(size_t first, size_t last) {
    uint32_t ids[kChunk * 8];
    Vec3f corners[kChunk * 8 * 3];
    size_t n = 0;
    for (size_t i = first; i < last; ++i) {
      Placed& leaf = leaves_[i];
      if (repeats_) drop_repeats(leaf);
      for (uint32_t k = 0; k < leaf.count; ++k) ids[n++] = refs_[leaf.ref + k].prim_id;
    }
    corners_.gather(std::span(ids, n), corners);
    std::vector<float> words;
    words.reserve(n * 6 + (last - first) * 8);  // about 5.8 words per primitive, 3 per vertex
    n = 0;
    for (size_t i = first; i < last; ++i) {
      Placed& leaf = leaves_[i];
      const std::span<const Vec3f> c(corners + 3 * n, 3 * size_t(leaf.count));
      const CornerIndex index = index_corners(c);
      leaf.offset = uint32_t(words.size());
      words.resize(words.size() + leaf_words(leaf.count, index.v));
      store_leaf(words.data() + leaf.offset, c, std::span(ids + n, leaf.count), index);
      n += leaf.count;
    }
    return words;
  }

  /// Keeps the first ref of each primitive in the leaf's range (with spatial splits, pieces of
  /// one triangle can meet again in a leaf that took a whole subtree). The plan allows at
  /// most max_leaf refs where the subtree began, and every piece below comes from one of
  /// those, so at most max_leaf primitives remain.
  void drop_repeats(Placed& leaf) {
    uint32_t kept = 0;
    for (uint32_t k = 0; k < leaf.count; ++k) {
      const PrimRef r = refs_[leaf.ref + k];
      bool seen = false;
      for (uint32_t j = 0; j < kept; ++j) seen |= refs_[leaf.ref + j].prim_id == r.prim_id;
      if (!seen) refs_[leaf.ref + kept++] = r;
    }
    RP_CHECK(kept <= 8, "bvh8: a leaf of ", kept, " primitives");
    leaf.count = kept;
  }

  const CornerSource& corners_;
  RefArray& refs_;
  Bvh8& out_;
  bool repeats_;
  std::vector<Placed> leaves_;  ///< numbered by lay_out; their offsets (words) by fill
};

/// SAH cost of the 8-wide tree (see BuildStats::sah_cost).
double sah_cost(const Bvh8& t) {
  const double root = t.bounds.area();
  if (t.empty() || !(root > 0)) return 0;
  double cost = 1.0;  // the root
  for (const Bvh8Node& n : t.nodes)
    for (int k = 0; k < 8 && n.child[k] != kEmpty; ++k) {
      const Box3f b({n.lo_x[k], n.lo_y[k], n.lo_z[k]}, {n.hi_x[k], n.hi_y[k], n.hi_z[k]});
      if (is_leaf(n.child[k])) {
        cost += b.area() / root * (kLeafCost + kPrimCost * double(t.leaf(n.child[k]).n));
      } else {
        cost += b.area() / root * kTraversalCost;
      }
    }
  return cost;
}

}  // namespace

uint32_t write_leaf(float* out, std::span<const Vec3f> corners, std::span<const uint32_t> ids) {
  RP_CHECK(ids.size() >= 1 && ids.size() <= 8 && corners.size() == 3 * ids.size(), "bvh8: a leaf of ", ids.size(),
           " primitives and ", corners.size(), " corners");
  const CornerIndex index = index_corners(corners);
  store_leaf(out, corners, ids, index);
  return index.v;
}

namespace {

/// The tree over `refs` (the primitives of `what`, ids in the scene's numbering), timed from
/// `start`.
Bvh8 build_refs(const Scene& scene, RefArray refs, const BuildOptions& options, const Selection& what,
                std::chrono::steady_clock::time_point start) {
  const uint32_t first_analytic = scene.sphere_base();
  Bvh8 out;
  out.stats.prims = uint32_t(refs.size());
  if (!refs.empty()) {
    const bool spatial = options.spatial_splits && options.rule == SplitRule::sah;
    const CornerSource corners(scene, spatial, what);
    Builder builder(corners, refs, options, first_analytic);
    const BuildNode& root = builder.build();
    out.bounds = root.box;
    Collapser collapser(corners, refs, out, spatial);
    collapser.root(root);
    collapser.fill();
  }
  out.first_analytic = first_analytic;
  out.has_analytic = what.mesh == Selection::kWorld && scene.plane_base() > scene.sphere_base();
  out.stats.nodes = uint32_t(out.nodes.size());
  out.stats.sah_cost = sah_cost(out);
  out.stats.bytes = out.nodes.size() * sizeof(Bvh8Node) + out.leaf_data.size() * sizeof(float);
  out.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

/// Refs for the triangles of mesh m at refs[at + t] (zero-area ones marked kInvalidId, to be
/// dropped); returns how many were zero-area.
size_t triangle_refs(const Scene& scene, size_t m, RefArray& refs, size_t at) {
  const TriangleMesh& mesh = scene.meshes()[m];
  const uint32_t base = scene.mesh_base(m);
  std::atomic<size_t> degenerate{0};
  tbb::parallel_for(tbb::blocked_range<uint32_t>(0, mesh.triangle_count(), 4096), [&](const tbb::blocked_range<uint32_t>& r) {
    size_t zero_area = 0;
    for (uint32_t t = r.begin(); t < r.end(); ++t) {
      const Vec3f a = mesh.vertex(t, 0), b = mesh.vertex(t, 1), c = mesh.vertex(t, 2);
      const Vec3f n = cross(b - a, c - a);
      const bool keep = !(n.x == 0.0f && n.y == 0.0f && n.z == 0.0f);  // zero area: never hit
      zero_area += !keep;
      Box3f box;
      box.extend(a);
      box.extend(b);
      box.extend(c);
      refs[at + t] = PrimRef::make(box, keep ? base + t : kInvalidId);
    }
    degenerate += zero_area;
  });
  return degenerate;
}

void drop_invalid(RefArray& refs) {
  refs.erase(std::remove_if(refs.begin(), refs.end(), [](const PrimRef& r) { return r.prim_id == kInvalidId; }),
             refs.end());
}

}  // namespace

Bvh8 build(const Scene& scene, const BuildOptions& options) {
  RP_CHECK(options.max_leaf >= 1 && options.max_leaf <= 8, "bvh8: max_leaf ", options.max_leaf,
           " must be in 1..8");
  const auto start = std::chrono::steady_clock::now();
  // References in parallel (the array's pages first touched there), then the zero-area
  // triangles and the instanced meshes' (which are not in the world), marked kInvalidId,
  // dropped in order.
  RefArray refs(scene.plane_base());  // triangles, then spheres, quadrics and polygons
  size_t dropped = 0;
  for (size_t m = 0; m < scene.meshes().size(); ++m) {
    if (scene.is_instanced(m)) {
      const uint32_t base = scene.mesh_base(m), n = scene.meshes()[m].triangle_count();
      for (uint32_t t = 0; t < n; ++t) refs[base + t].prim_id = kInvalidId;
      dropped += n;
    } else {
      dropped += triangle_refs(scene, m, refs, scene.mesh_base(m));
    }
  }
  for (uint32_t id = scene.sphere_base(); id < scene.plane_base(); ++id) refs[id] = PrimRef::make(scene.prim_bounds(id), id);
  if (dropped > 0) drop_invalid(refs);
  return build_refs(scene, std::move(refs), options, Selection{}, start);
}

Bvh8 build_mesh(const Scene& scene, uint32_t mesh, const BuildOptions& options) {
  RP_CHECK(options.max_leaf >= 1 && options.max_leaf <= 8, "bvh8: max_leaf ", options.max_leaf,
           " must be in 1..8");
  RP_CHECK(mesh < scene.meshes().size(), "bvh8: mesh ", mesh, " out of range");
  const auto start = std::chrono::steady_clock::now();
  RefArray refs(scene.meshes()[mesh].triangle_count());
  if (triangle_refs(scene, mesh, refs, 0) > 0) drop_invalid(refs);
  return build_refs(scene, std::move(refs), options, Selection{mesh}, start);
}

float mean_leaf_size(const Bvh8& bvh) {
  double area = 0.0;
  size_t leaves = 0;
  for (const Bvh8Node& n : bvh.nodes)
    for (int c = 0; c < 8 && n.child[c] != kEmpty; ++c) {
      if (!is_leaf(n.child[c])) continue;
      const double dx = double(n.hi_x[c]) - n.lo_x[c], dy = double(n.hi_y[c]) - n.lo_y[c],
                   dz = double(n.hi_z[c]) - n.lo_z[c];
      area += 2.0 * (dx * dy + dy * dz + dz * dx);
      ++leaves;
    }
  return leaves ? float(std::sqrt(area / double(leaves) / 6.0)) : 0.0f;
}

InstanceTree build_instances(const Scene& scene) {
  const auto start = std::chrono::steady_clock::now();
  InstanceTree out;
  RefArray refs;
  for (uint32_t i = 0; i < scene.instances().size(); ++i) {
    const Instance& in = scene.instances()[i];
    if (in.bounds.empty()) continue;  // a mesh without triangles
    // Grown by 2^-16 of the box's size and place, times the transform's condition: the
    // object-space ray is rounded (rp::object_ray), and a hit it finds must not lie outside
    // the box a traversal culls by (see InstanceTree).
    const Affine3d w(in.world_to_object), m(in.object_to_world);
    const double cond = m.linear_norm() * w.linear_norm();
    const Box3d b(Vec3d(in.bounds.lo), Vec3d(in.bounds.hi));
    const double size = max_component(b.extent()) + std::max(max_component(abs(b.lo)), max_component(abs(b.hi)));
    refs.push_back(PrimRef::make(outward(b, 0x1p-16 * cond * size), i));
  }
  out.stats.prims = uint32_t(refs.size());
  if (!refs.empty()) {
    // Every instance a leaf of its own (all refs "analytic" to the builder), by SAH.
    const BuildOptions one{.rule = SplitRule::sah, .max_leaf = 1, .spatial_splits = false};
    const CornerSource corners(scene, false, Selection{});
    Builder builder(corners, refs, one, 0);
    const BuildNode& root = builder.build();
    out.bounds = root.box;
    Bvh8 tree;
    Collapser collapser(corners, refs, tree, false);
    collapser.root(root);
    collapser.point_at_refs();
    out.nodes = std::move(tree.nodes);
    out.stats.depth = tree.stats.depth;
    out.stats.leaves = tree.stats.leaves;
  }
  out.stats.nodes = uint32_t(out.nodes.size());
  out.stats.bytes = out.nodes.size() * sizeof(Bvh8Node);
  out.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace rp::bvh8
