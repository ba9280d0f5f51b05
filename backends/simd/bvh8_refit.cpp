/// Refitting a built tree to moved vertices (bvh8.h: refit): the leaves' vertex blocks and
/// boxes in parallel, node by node, then the inner boxes bottom-up.

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <atomic>
#include <bit>
#include <tuple>
#include <utility>

#include "backends/simd/bvh8.h"
#include "backends/simd/bvh8_costs.h"
#include "base/error.h"

namespace rp::bvh8 {

namespace {

/// Where the corners of a tree's triangles are: the scene's meshes, by prim_id (the world's
/// tree, or one instanced mesh's). Walks a leaf's triangles remembering the mesh of the last
/// one (a leaf's triangles nearly always share a mesh), so a mesh is looked up once per leaf.
class TreeTriangles {
 public:
  TreeTriangles(const Scene& scene, uint32_t mesh) : scene_(scene) {
    if (mesh != kInvalidId) take(mesh);
  }

  /// The index row of triangle `prim` and its mesh's positions.
  std::pair<const TriangleIndices*, const Strided<Vec3f>*> row(uint32_t prim) {
    if (prim - first_ >= count_) take(scene_.locate(prim).shape);
    return {&mesh_->triangles[prim - first_], &mesh_->positions};
  }

 private:
  void take(uint32_t m) {
    mesh_ = &scene_.meshes()[m];
    first_ = scene_.mesh_base(m);
    count_ = mesh_->triangle_count();
  }

  const Scene& scene_;
  const MeshView* mesh_ = nullptr;
  uint32_t first_ = 0, count_ = 0;  ///< the prim_ids of mesh_: [first_, first_ + count_)
};

/// Rewrites the vertex block of the leaf at `words` from its triangles' current corners and
/// returns its box; sets `conflict` when two corners that share a slot now differ.
Box3f refit_leaf(float* words, TreeTriangles& tris, bool& conflict) {
  const Leaf leaf(words);
  float* x = words + (3 * leaf.n + 4) / 4 + leaf.n;
  float* y = x + leaf.v;
  float* z = y + leaf.v;
  // The rows first, then the corners they name: the scattered reads start together.
  const TriangleIndices* rows[8];
  const Strided<Vec3f>* positions[8];
  for (uint32_t k = 0; k < leaf.n; ++k) std::tie(rows[k], positions[k]) = tris.row(leaf.prim(k));
  uint32_t written = 0;  // slots written so far, one bit each (at most 24)
  Box3f box;
  for (uint32_t k = 0; k < leaf.n; ++k)
    for (uint32_t j = 0; j < 3; ++j) {
      const Vec3f c = (*positions[k])[(*rows[k])[j]];
      const uint32_t i = leaf.corners(j)[k];
      box.extend(c);
      if (written >> i & 1u) {
        conflict |= std::bit_cast<uint32_t>(x[i]) != std::bit_cast<uint32_t>(c.x) ||
                    std::bit_cast<uint32_t>(y[i]) != std::bit_cast<uint32_t>(c.y) ||
                    std::bit_cast<uint32_t>(z[i]) != std::bit_cast<uint32_t>(c.z);
        continue;
      }
      written |= 1u << i;
      x[i] = c.x;
      y[i] = c.y;
      z[i] = c.z;
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
  if (bvh.empty()) return Refit::done;
  std::atomic<bool> conflict{false};
  tbb::parallel_for(tbb::blocked_range<size_t>(0, bvh.nodes.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
    TreeTriangles tris(scene, mesh);
    bool clash = false;
    for (size_t i = r.begin(); i < r.end(); ++i) {
      Bvh8Node& n = bvh.nodes[i];
      for (int k = 0; k < 8 && n.child[k] != kEmpty; ++k) {
        if (!is_leaf(n.child[k])) continue;
        const Leaf leaf = bvh.leaf(n.child[k]);
        if (bvh.has_analytic && leaf.n == 1 && leaf.prim(0) >= bvh.first_analytic) continue;  // does not move
        set_box(n, k, refit_leaf(bvh.leaf_data.data() + leaf_offset(n.child[k]), tris, clash));
      }
    }
    if (clash) conflict.store(true, std::memory_order_relaxed);
  });
  if (conflict.load()) return Refit::rebuild;
  // A triangle left out for zero area that has area now is in no leaf.
  for (uint32_t id : bvh.zero_area) {
    const PrimLocation at = scene.locate(id);
    const MeshView& m = scene.meshes()[at.shape];
    const Vec3f a = m.vertex(at.local, 0), n = cross(m.vertex(at.local, 1) - a, m.vertex(at.local, 2) - a);
    if (!(n.x == 0.0f && n.y == 0.0f && n.z == 0.0f)) return Refit::rebuild;
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
  for (uint32_t& id : bvh.zero_area) id = id - from + to;
}

}  // namespace rp::bvh8
