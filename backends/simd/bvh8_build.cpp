#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <chrono>
#include <memory>

#include "backends/simd/bvh8.h"
#include "engine/error.h"

namespace rp::bvh8 {

namespace {

/// A primitive's box and the point the splits sort it by (triangle centroid, the seeds'
/// "centre of mass"; box centre for analytic primitives).
struct PrimRef {
  Box3f box;
  Vec3f centroid;
  uint32_t prim_id;
};

/// Binary build tree: a leaf has no children and owns refs[begin, end).
struct BuildNode {
  Box3f box;
  uint32_t begin = 0, end = 0;
  std::unique_ptr<BuildNode> left, right;
  bool leaf() const { return !left; }
};

constexpr int kBins = 16;
constexpr float kTraversalCost = 1.0f;     ///< SAH cost of visiting a node
constexpr float kIntersectionCost = 1.0f;  ///< SAH cost of one primitive test
constexpr uint32_t kParallelThreshold = 4096;
constexpr uint32_t kMaxSahDepth = 64;  ///< deeper than this, median splits bound the depth

class Builder {
 public:
  Builder(std::vector<PrimRef>& refs, const BuildOptions& o) : refs_(refs), opt_(o) {}

  std::unique_ptr<BuildNode> build(uint32_t begin, uint32_t end, uint32_t depth) {
    auto node = std::make_unique<BuildNode>();
    node->begin = begin;
    node->end = end;
    Box3f centroids;
    for (uint32_t i = begin; i < end; ++i) {
      node->box.extend(refs_[i].box);
      centroids.extend(refs_[i].centroid);
    }
    const uint32_t n = end - begin;
    if (n <= 1) return node;
    uint32_t mid = 0;
    if (opt_.rule == SplitRule::sah && depth < kMaxSahDepth) {
      mid = sah_split(begin, end, node->box, centroids);
      if (mid == begin) return node;  // SAH prefers a leaf
    } else {
      if (n <= opt_.max_leaf) return node;
      mid = median_split(begin, end, node->box);
    }
    if (n > kParallelThreshold) {
      tbb::parallel_invoke([&] { node->left = build(begin, mid, depth + 1); },
                           [&] { node->right = build(mid, end, depth + 1); });
    } else {
      node->left = build(begin, mid, depth + 1);
      node->right = build(mid, end, depth + 1);
    }
    return node;
  }

 private:
  /// Binned SAH (Wald, "On fast Construction of SAH-based Bounding Volume Hierarchies", 2007):
  /// 16 bins per axis over the centroid bounds. Returns the split index, or `begin` when a
  /// leaf is cheaper (only allowed for at most max_leaf primitives).
  uint32_t sah_split(uint32_t begin, uint32_t end, const Box3f& box, const Box3f& centroids) {
    const uint32_t n = end - begin;
    const Vec3f extent = centroids.extent();
    float best_cost = std::numeric_limits<float>::infinity();
    int best_axis = -1, best_bin = 0;
    for (int axis = 0; axis < 3; ++axis) {
      if (!(extent[axis] > 0.0f)) continue;
      const float scale = float(kBins) / extent[axis];
      Box3f bin_box[kBins];
      uint32_t bin_count[kBins] = {};
      for (uint32_t i = begin; i < end; ++i) {
        const int b = bin_of(refs_[i].centroid[axis], centroids.lo[axis], scale);
        bin_box[b].extend(refs_[i].box);
        ++bin_count[b];
      }
      float right_area[kBins];
      uint32_t right_count[kBins];
      Box3f acc;
      uint32_t count = 0;
      for (int b = kBins - 1; b > 0; --b) {
        acc.extend(bin_box[b]);
        count += bin_count[b];
        right_area[b] = acc.area();
        right_count[b] = count;
      }
      acc = Box3f();
      count = 0;
      for (int b = 1; b < kBins; ++b) {
        acc.extend(bin_box[b - 1]);
        count += bin_count[b - 1];
        if (count == 0 || right_count[b] == 0) continue;
        const float cost = acc.area() * float(count) + right_area[b] * float(right_count[b]);
        if (cost < best_cost) {
          best_cost = cost;
          best_axis = axis;
          best_bin = b;
        }
      }
    }
    const float area = box.area();
    const float split_cost = area > 0.0f ? kTraversalCost + kIntersectionCost * best_cost / area
                                         : std::numeric_limits<float>::infinity();
    if (n <= opt_.max_leaf && kIntersectionCost * float(n) <= split_cost) return begin;
    if (best_axis < 0) return object_median(begin, end);  // every centroid coincides
    const float lo = centroids.lo[best_axis], scale = float(kBins) / extent[best_axis];
    PrimRef* first = refs_.data() + begin;
    PrimRef* mid = std::partition(first, refs_.data() + end, [&](const PrimRef& r) {
      return bin_of(r.centroid[best_axis], lo, scale) < best_bin;
    });
    const uint32_t m = uint32_t(mid - refs_.data());
    return (m == begin || m == end) ? object_median(begin, end) : m;
  }

  /// The seeds' rule: split the longest axis of the node's box at the median centroid, so
  /// both halves hold the same number of primitives.
  uint32_t median_split(uint32_t begin, uint32_t end, const Box3f& box) {
    const int axis = max_abs_axis(box.extent());
    const uint32_t mid = begin + (end - begin) / 2;
    std::nth_element(refs_.begin() + begin, refs_.begin() + mid, refs_.begin() + end,
                     [axis](const PrimRef& a, const PrimRef& b) {
                       return a.centroid[axis] < b.centroid[axis] ||
                              (a.centroid[axis] == b.centroid[axis] && a.prim_id < b.prim_id);
                     });
    return mid;
  }

  uint32_t object_median(uint32_t begin, uint32_t end) { return begin + (end - begin) / 2; }

  static int bin_of(float c, float lo, float scale) {
    return std::clamp(int((c - lo) * scale), 0, kBins - 1);
  }

  std::vector<PrimRef>& refs_;
  const BuildOptions& opt_;
};

/// Collapses the binary tree into 8-wide nodes (pre-order, single-threaded, so the layout is
/// deterministic): a node takes its two children, then keeps opening the inner child with the
/// largest surface area until it has 8 children or only leaves.
class Collapser {
 public:
  Collapser(const Scene& scene, const std::vector<PrimRef>& refs, Bvh8& out) : scene_(scene), refs_(refs), out_(out) {}

  void root(const BuildNode& bn) {
    if (bn.leaf()) {  // a one-leaf tree still needs a root node
      out_.nodes.emplace_back();
      clear(out_.nodes[0]);
      set_child(0, 0, bn, emit_leaf(bn));
      out_.stats.depth = 1;
      return;
    }
    collapse(bn, 1);
  }

 private:
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

  int32_t collapse(const BuildNode& bn, uint32_t depth) {
    out_.stats.depth = std::max(out_.stats.depth, depth);
    std::vector<const BuildNode*> kids{bn.left.get(), bn.right.get()};
    while (kids.size() < 8) {
      int open = -1;
      float area = -1.0f;
      for (size_t k = 0; k < kids.size(); ++k)
        if (!kids[k]->leaf() && kids[k]->box.area() > area) {
          area = kids[k]->box.area();
          open = int(k);
        }
      if (open < 0) break;
      const BuildNode* o = kids[size_t(open)];
      kids[size_t(open)] = o->left.get();
      kids.insert(kids.begin() + open + 1, o->right.get());
    }
    const size_t index = out_.nodes.size();
    out_.nodes.emplace_back();
    clear(out_.nodes[index]);
    for (size_t k = 0; k < kids.size(); ++k) {
      const int32_t ref = kids[k]->leaf() ? emit_leaf(*kids[k]) : collapse(*kids[k], depth + 1);
      set_child(index, int(k), *kids[k], ref);  // nodes may have grown: index, not a reference
    }
    return int32_t(index);
  }

  int32_t emit_leaf(const BuildNode& bn) {
    Bvh8Leaf leaf;
    leaf.tri_first = tri_slots_;
    leaf.other_first = uint32_t(out_.others.size());
    for (uint32_t i = bn.begin; i < bn.end; ++i) {
      const uint32_t id = refs_[i].prim_id;
      if (id < scene_.triangle_count()) {
        store_triangle(tri_slots_++, id);
        ++leaf.tri_count;
      } else {
        out_.others.push_back(id);
        ++leaf.other_count;
      }
    }
    out_.leaves.push_back(leaf);
    return ~int32_t(out_.leaves.size() - 1);
  }

  void store_triangle(uint32_t slot, uint32_t prim_id) {
    if (slot / 8 >= out_.tris.size()) {
      out_.tris.emplace_back();
      Tri8& b = out_.tris.back();
      std::fill_n(&b.v0_x[0], 9 * 8, 0.0f);
      std::fill_n(b.prim_id, 8, kInvalidId);
    }
    const auto ref = scene_.locate(prim_id);
    const TriangleMesh& m = scene_.meshes()[ref.shape];
    const Vec3f v0 = m.vertex(ref.local, 0);
    const Vec3f e1 = m.vertex(ref.local, 1) - v0;  // as intersect_triangle_mt computes them
    const Vec3f e2 = m.vertex(ref.local, 2) - v0;
    Tri8& b = out_.tris[slot / 8];
    const uint32_t l = slot % 8;
    b.v0_x[l] = v0.x; b.v0_y[l] = v0.y; b.v0_z[l] = v0.z;
    b.e1_x[l] = e1.x; b.e1_y[l] = e1.y; b.e1_z[l] = e1.z;
    b.e2_x[l] = e2.x; b.e2_y[l] = e2.y; b.e2_z[l] = e2.z;
    b.prim_id[l] = prim_id;
  }

  const Scene& scene_;
  const std::vector<PrimRef>& refs_;
  Bvh8& out_;
  uint32_t tri_slots_ = 0;
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
        const Bvh8Leaf& l = t.leaves[size_t(~n.child[k])];
        cost += b.area() / root * kIntersectionCost * double(l.tri_count + l.other_count);
      } else {
        cost += b.area() / root * kTraversalCost;
      }
    }
  return cost;
}

}  // namespace

Bvh8 build(const Scene& scene, const BuildOptions& options) {
  RP_CHECK(options.max_leaf >= 1 && options.max_leaf <= 8, "bvh8: max_leaf ", options.max_leaf,
           " must be in 1..8");
  const auto start = std::chrono::steady_clock::now();
  std::vector<PrimRef> refs;
  refs.reserve(scene.triangle_count() + scene.spheres().size() + scene.quadrics().size() + scene.polygons().size());
  for (size_t m = 0; m < scene.meshes().size(); ++m) {
    const TriangleMesh& mesh = scene.meshes()[m];
    for (uint32_t t = 0; t < mesh.triangle_count(); ++t) {
      const Vec3f a = mesh.vertex(t, 0), b = mesh.vertex(t, 1), c = mesh.vertex(t, 2);
      const Vec3f n = cross(b - a, c - a);
      if (n.x == 0.0f && n.y == 0.0f && n.z == 0.0f) continue;  // zero area: never hit
      PrimRef r;
      r.box.extend(a);
      r.box.extend(b);
      r.box.extend(c);
      r.centroid = (a + b + c) * (1.0f / 3.0f);
      r.prim_id = scene.mesh_base(m) + t;
      refs.push_back(r);
    }
  }
  for (uint32_t id = scene.sphere_base(); id < scene.plane_base(); ++id) {
    PrimRef r;
    r.box = scene.prim_bounds(id);
    r.centroid = r.box.center();
    r.prim_id = id;
    refs.push_back(r);
  }
  Bvh8 out;
  out.stats.prims = uint32_t(refs.size());
  if (!refs.empty()) {
    Builder builder(refs, options);
    const std::unique_ptr<BuildNode> root = builder.build(0, uint32_t(refs.size()), 0);
    out.bounds = root->box;
    Collapser(scene, refs, out).root(*root);
  }
  out.stats.nodes = uint32_t(out.nodes.size());
  out.stats.leaves = uint32_t(out.leaves.size());
  out.stats.sah_cost = sah_cost(out);
  out.stats.bytes = out.nodes.size() * sizeof(Bvh8Node) + out.leaves.size() * sizeof(Bvh8Leaf) +
                    out.tris.size() * sizeof(Tri8) + out.others.size() * sizeof(uint32_t);
  out.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace rp::bvh8
