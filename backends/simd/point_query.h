#pragma once
/// The simd backend's closest-point query (core/queries.h): the loop of the point shape. One
/// point against the 8 child boxes of a node at a time (squared distances, 8 wide), nearest
/// child first, subtrees farther than the closest point so far skipped; both levels (levels.h):
/// an instance takes the point into its object space and walks its mesh's tree there, the
/// boxes' distances scaled by a lower bound of the instance's stretch, each triangle's point
/// found in the world (closest_on_placed_triangle), as every backend finds it.
/// AVX2+FMA translation units only.

#include <cmath>

#include "backends/simd/levels.h"
#include "core/geometry/closest_point.h"
#include "core/queries.h"

namespace rp::bvh8 {

/// Squared distances from point (px, py, pz) to the 8 child boxes of `n` (+inf for a missing
/// child, whose box is empty).
RP_SIMD_INLINE float8 box_distance2(const Bvh8Node& n, const float8& px, const float8& py, const float8& pz) {
  const float8 zero(0.0f);
  const float8 dx = xsimd::max(xsimd::max(float8::load_aligned(n.lo_x) - px, px - float8::load_aligned(n.hi_x)), zero);
  const float8 dy = xsimd::max(xsimd::max(float8::load_aligned(n.lo_y) - py, py - float8::load_aligned(n.hi_y)), zero);
  const float8 dz = xsimd::max(xsimd::max(float8::load_aligned(n.lo_z) - pz, pz - float8::load_aligned(n.hi_z)), zero);
  return xsimd::fma(dx, dx, xsimd::fma(dy, dy, dz * dz));
}

/// Walks the tree of `nodes` (root 0) from point q (the tree's space), nearest child first,
/// calling leaf(ref) for each leaf whose box is within the search's limit; a box's squared
/// distance counts times `scale2` (1 in the world; an instance's lower bound of its stretch).
template <class Nodes, class Leaf>
void walk_points(const Nodes& nodes, const Vec3f& q, float scale2, PointSearch& s, Leaf&& leaf) {
  struct Entry {
    int32_t ref;
    float d2;
  };
  Entry stack[kStackSize];
  int sp = 0;
  stack[sp++] = {0, 0.0f};
  const float8 px(q.x), py(q.y), pz(q.z);
  while (sp) {
    const Entry e = stack[--sp];
    if (e.d2 * scale2 > s.limit2) continue;
    if (is_leaf(e.ref)) {
      leaf(e.ref);
      continue;
    }
    const Bvh8Node& n = nodes[size_t(e.ref)];
    alignas(32) float d2[8];
    box_distance2(n, px, py, pz).store_aligned(d2);
    // The children within the limit, pushed farthest first so the nearest is popped next.
    Entry near[8];
    int k = 0;
    for (int c = 0; c < 8; ++c) {
      if (n.child[c] == kEmpty || d2[c] * scale2 > s.limit2) continue;
      int j = k++;
      for (; j > 0 && near[j - 1].d2 < d2[c]; --j) near[j] = near[j - 1];
      near[j] = {n.child[c], d2[c]};
    }
    RP_DCHECK(sp + k <= kStackSize);
    for (int j = 0; j < k; ++j) stack[sp++] = near[j];
  }
}

/// The leaf `ref` of mesh tree `bvh` placed by instance `inst` (`object_to_world`; null and
/// kNoInstance for the world's tree) against the search.
inline void closest_in_leaf(const Bvh8& bvh, const Scene& scene, int32_t ref, uint32_t inst,
                            const Affine3f* object_to_world, PointSearch& s) {
  const Leaf leaf = bvh.leaf(ref);
  if (leaf.n == 1 && bvh.has_analytic && leaf.prim(0) >= bvh.first_analytic) {
    s.take(scene.closest_on_analytic(leaf.prim(0), s.point));
    return;
  }
  for (uint32_t k = 0; k < leaf.n; ++k) {
    if (zero_area(leaf.vertex(k, 0), leaf.vertex(k, 1), leaf.vertex(k, 2))) continue;  // after a refit
    const SurfacePointT<float> c =
        closest_on_placed_triangle(s.point, leaf.vertex(k, 0), leaf.vertex(k, 1), leaf.vertex(k, 2), object_to_world);
    s.take({c.p, length(c.p - s.point), leaf.prim(k), inst, c.u, c.v});
  }
}

/// The closest point of the world's tree `world` and of the instances (`tree`, `placed`) to
/// the query of `s`.
inline void closest_point(const Bvh8& world, const InstanceTree& tree, std::span<const Placed> placed,
                          const Scene& scene, PointSearch& s) {
  if (!world.empty())
    walk_points(world.nodes, s.point, 1.0f, s,
                [&](int32_t ref) { closest_in_leaf(world, scene, ref, kNoInstance, nullptr, s); });
  if (tree.empty()) return;
  walk_points(tree.nodes, s.point, 1.0f, s, [&](int32_t ref) {
    const uint32_t i = leaf_offset(ref);
    const Placed& in = placed[i];
    if (in.mesh->empty()) return;
    const Affine3f& w2o = in.world_to_object;
    // |object_to_world v| >= |v| / (the largest stretch of world_to_object): an object-space
    // distance over that bound never exceeds the world distance.
    const float stretch = w2o.largest_stretch();
    const float scale2 = 1.0f / (stretch * stretch * 1.00001f);
    const Affine3f& o2w = scene.instances()[i].object_to_world;
    walk_points(in.mesh->nodes, w2o.point(s.point), scale2, s,
                [&](int32_t leaf) { closest_in_leaf(*in.mesh, scene, leaf, i, &o2w, s); });
  });
}

}  // namespace rp::bvh8
