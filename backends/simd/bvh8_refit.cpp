/// Refitting a built tree to moved vertices (bvh8.h: refit): the leaves' vertex blocks and
/// boxes in parallel, node by node, then the inner boxes bottom-up.

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <atomic>
#include <bit>
#include <chrono>
#include <memory>

#include "backends/simd/bvh8.h"
#include "backends/simd/bvh8_costs.h"
#include "base/error.h"

namespace rp::bvh8 {

namespace {

/// Where the corners of a tree's triangles are: the scene's meshes, by prim_id (the world's
/// tree, or one instanced mesh's).
class TreeTriangles {
 public:
  TreeTriangles(const Scene& scene, uint32_t mesh)
      : scene_(scene), mesh_(mesh), first_(mesh == kInvalidId ? 0 : scene.mesh_base(mesh)) {}

  /// The corners of triangle `prim` of the tree.
  void corners(uint32_t prim, Vec3f out[3]) const {
    uint32_t m = mesh_, local = prim - first_;
    if (mesh_ == kInvalidId) {
      const PrimLocation at = scene_.locate(prim);
      m = at.shape;
      local = at.local;
    }
    const TriangleMesh& tm = scene_.meshes()[m];
    const uint32_t* row = tm.indices.data() + 3 * size_t(local);
    for (int j = 0; j < 3; ++j) out[j] = tm.positions[row[j]];
  }

  /// Calls f(index, a, b, c) for every triangle the tree was built over (zero-area ones
  /// included), in parallel; index: the prim_id less the tree's first.
  template <typename F>
  void for_each(F f) const {
    for (uint32_t m = 0; m < scene_.meshes().size(); ++m) {
      if (mesh_ == kInvalidId ? scene_.is_instanced(m) : m != mesh_) continue;
      const TriangleMesh& tm = scene_.meshes()[m];
      const uint32_t base = scene_.mesh_base(m) - first_;
      tbb::parallel_for(tbb::blocked_range<uint32_t>(0, tm.triangle_count(), 4096),
                        [&](const tbb::blocked_range<uint32_t>& r) {
                          for (uint32_t t = r.begin(); t < r.end(); ++t)
                            f(base + t, tm.vertex(t, 0), tm.vertex(t, 1), tm.vertex(t, 2));
                        });
    }
  }

  /// How many triangles the tree's ids number (the size of a table indexed by them).
  uint32_t id_count() const {
    return mesh_ == kInvalidId ? scene_.triangle_count() : scene_.meshes()[mesh_].triangle_count();
  }
  /// The prim_id of the tree's first triangle.
  uint32_t first() const { return first_; }

 private:
  const Scene& scene_;
  uint32_t mesh_, first_;
};

/// Rewrites the vertex block of the leaf at `words` from the triangles' current corners and
/// returns its box; `conflict` is set when two corners that share a slot now differ. Marks
/// each triangle in `seen` (when not null).
Box3f refit_leaf(float* words, const TreeTriangles& tris, std::atomic<uint8_t>* seen, bool& conflict) {
  const Leaf leaf(words);
  float* x = words + (3 * leaf.n + 4) / 4 + leaf.n;
  float* y = x + leaf.v;
  float* z = y + leaf.v;
  uint32_t written = 0;  // slots written so far, one bit each (at most 24)
  Box3f box;
  for (uint32_t k = 0; k < leaf.n; ++k) {
    const uint32_t prim = leaf.prim(k);
    if (seen) seen[prim - tris.first()].store(1, std::memory_order_relaxed);
    Vec3f c[3];
    tris.corners(prim, c);
    for (uint32_t j = 0; j < 3; ++j) {
      const uint32_t i = leaf.corners(j)[k];
      box.extend(c[j]);
      if (written >> i & 1u) {
        conflict |= std::bit_cast<uint32_t>(x[i]) != std::bit_cast<uint32_t>(c[j].x) ||
                    std::bit_cast<uint32_t>(y[i]) != std::bit_cast<uint32_t>(c[j].y) ||
                    std::bit_cast<uint32_t>(z[i]) != std::bit_cast<uint32_t>(c[j].z);
        continue;
      }
      written |= 1u << i;
      x[i] = c[j].x;
      y[i] = c[j].y;
      z[i] = c[j].z;
    }
  }
  return box;
}

void set_box(Bvh8Node& n, int k, const Box3f& b) {
  n.lo_x[k] = b.lo.x;
  n.lo_y[k] = b.lo.y;
  n.lo_z[k] = b.lo.z;
  n.hi_x[k] = b.hi.x;
  n.hi_y[k] = b.hi.y;
  n.hi_z[k] = b.hi.z;
}

/// The union of a node's child boxes.
Box3f node_box(const Bvh8Node& n) {
  Box3f b;
  for (int k = 0; k < 8 && n.child[k] != kEmpty; ++k) {
    b.extend(Vec3f{n.lo_x[k], n.lo_y[k], n.lo_z[k]});
    b.extend(Vec3f{n.hi_x[k], n.hi_y[k], n.hi_z[k]});
  }
  return b;
}

}  // namespace

Refit refit(Bvh8& bvh, const Scene& scene, uint32_t mesh, double limit) {
  const auto start = std::chrono::steady_clock::now();
  if (bvh.empty()) return Refit::done;
  const TreeTriangles tris(scene, mesh);
  // Only a tree that left zero-area triangles out needs to know which are in it.
  std::unique_ptr<std::atomic<uint8_t>[]> seen;
  if (bvh.stats.zero_area > 0) {
    seen = std::make_unique<std::atomic<uint8_t>[]>(tris.id_count());
    for (uint32_t i = 0; i < tris.id_count(); ++i) seen[i].store(0, std::memory_order_relaxed);
  }
  std::atomic<bool> conflict{false};
  tbb::parallel_for(tbb::blocked_range<size_t>(0, bvh.nodes.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
    bool clash = false;
    for (size_t i = r.begin(); i < r.end(); ++i) {
      Bvh8Node& n = bvh.nodes[i];
      for (int k = 0; k < 8 && n.child[k] != kEmpty; ++k) {
        if (!is_leaf(n.child[k])) continue;
        const Leaf leaf = bvh.leaf(n.child[k]);
        if (bvh.has_analytic && leaf.n == 1 && leaf.prim(0) >= bvh.first_analytic) continue;  // does not move
        set_box(n, k, refit_leaf(bvh.leaf_data.data() + leaf_offset(n.child[k]), tris, seen.get(), clash));
      }
    }
    if (clash) conflict.store(true, std::memory_order_relaxed);
  });
  if (conflict.load()) return Refit::rebuild;
  if (seen) {
    std::atomic<bool> missing{false};
    tris.for_each([&](uint32_t id, const Vec3f& a, const Vec3f& b, const Vec3f& c) {
      const Vec3f n = cross(b - a, c - a);
      if (!seen[id].load(std::memory_order_relaxed) && !(n.x == 0.0f && n.y == 0.0f && n.z == 0.0f))
        missing.store(true, std::memory_order_relaxed);
    });
    if (missing.load()) return Refit::rebuild;
  }
  // Inner boxes bottom-up: the collapse lays a node's children out after it.
  for (size_t i = bvh.nodes.size(); i-- > 0;) {
    Bvh8Node& n = bvh.nodes[i];
    for (int k = 0; k < 8 && n.child[k] != kEmpty; ++k) {
      const int32_t c = n.child[k];
      if (is_leaf(c)) continue;
      RP_CHECK(size_t(c) > i, "bvh8: refit needs children after their parent (node ", i, ", child ", c, ")");
      set_box(n, k, node_box(bvh.nodes[size_t(c)]));
    }
  }
  bvh.bounds = node_box(bvh.nodes[0]);
  bvh.stats.sah_cost = build_detail::sah_cost(bvh);
  bvh.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return bvh.stats.sah_cost > limit * bvh.stats.built_sah_cost ? Refit::rebuild : Refit::done;
}

void renumber(Bvh8& bvh, uint32_t from, uint32_t to) {
  if (from == to) return;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, bvh.nodes.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i)
      for (int32_t c : bvh.nodes[i].child) {
        if (!is_leaf(c)) continue;
        float* words = bvh.leaf_data.data() + leaf_offset(c);
        const Leaf leaf(words);
        float* ids = words + (3 * leaf.n + 4) / 4;
        for (uint32_t k = 0; k < leaf.n; ++k) ids[k] = std::bit_cast<float>(leaf.prim(k) - from + to);
      }
  });
}

}  // namespace rp::bvh8
