#pragma once
/// The two levels of trees the simd backend's traversal loops walk, as the loops see them.
/// AVX2+FMA translation units only.
///
/// Every loop (one per ray shape: single_ray.h, packet8.h, large_packet.h, stream.h) is a
/// template over a level and a query (queries.h). A level says what a tree's nodes are and
/// what its leaves hold:
/// - MeshLevel: a tree over primitives: the world's (Bvh8 of build()), or an instanced mesh's
///   (build_mesh) as instance `inst` places it. A leaf is tested by the query.
/// - InstanceLevel: the tree over the instances' world boxes (InstanceTree), whose leaf ~i is
///   instance i. A leaf takes the rays into the instance's object space by rp::object_ray
///   (core/affine.h: the direction not renormalised, so t stays the world t) and runs the
///   same loop and query at the MeshLevel of the instance's mesh, with the instance's id: the
///   hits of every instance and of the world's tree meet under one closest-hit rule.
/// A ray is traced into an instance only when its object-space image obeys the valid-ray rule
/// (core/ray.h); any other ray misses that instance, on every backend and in the reference.
///
/// The closest hit is the least (t, prim_id, instance_id): among primitives hit at exactly the
/// same t (a ray through a shared edge or vertex), the lowest prim_id, and among placements of
/// one primitive by several instances, the lowest instance id (kNoInstance, the largest, for
/// the world's own primitives). The rule does not depend on the order in which leaves or
/// instances are visited, so every ray shape gives every ray the same primitive, instance and
/// t, u, v bits. (The unbounded planes then take a hit at equal t, after any traversal:
/// Scene::intersect_planes.)

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <span>
#include <vector>

#include "backends/simd/bvh8.h"
#include "backends/simd/packet.h"
#include "backends/simd/slab.h"
#include "base/error.h"
#include "core/affine.h"
#include "core/scene.h"
#include "simd/prefetch.h"

namespace rp::bvh8 {

/// Traversal stack bound: the build keeps binary depth <= 64 + log2(n) < 100, so an 8-wide
/// tree holds at most 7 pending children per level.
inline constexpr int kStackSize = 1024;

/// A packet entry with at most this many active lanes continues as single rays.
inline constexpr int kSingleRayLanes = 2;

/// True when primitive `id` placed by instance `inst` comes before `best`'s in the
/// closest-hit rule's order at equal t (the top of this file).
inline bool before(uint32_t id, uint32_t inst, const Hit& best) {
  return id < best.prim_id || (id == best.prim_id && inst < best.instance_id);
}

/// A tree over primitives, as instance `inst` places them (kNoInstance: the world's tree).
template <class Kernel>
struct MeshLevel {
  const Bvh8& bvh;
  const Scene& scene;
  uint32_t inst = kNoInstance;

  bool empty() const noexcept { return bvh.empty(); }
  const Bvh8Node& node(int32_t ref) const noexcept { return bvh.nodes[size_t(ref)]; }
  const Box3f& bounds() const noexcept { return bvh.bounds; }

  /// The prim_id of `leaf` when it is an analytic primitive, else kInvalidId. The build gives
  /// an analytic primitive a leaf of its own, so a leaf is all triangles (one 8-wide test) or
  /// one analytic primitive (its scalar routine).
  uint32_t analytic_leaf(const Leaf& leaf) const noexcept {
    if (leaf.n != 1 || !bvh.has_analytic) return kInvalidId;
    const uint32_t id = leaf.prim(0);
    return id >= bvh.first_analytic ? id : kInvalidId;
  }

  /// Starts loading the nodes (or leaf blocks) of the children in `bits`, which traversal is
  /// about to visit or push: hides part of the memory latency that dominates traversal.
  void prefetch_children(const Bvh8Node& n, uint32_t bits) const noexcept {
    for (; bits; bits &= bits - 1) {
      const int32_t c = n.child[std::countr_zero(bits)];
      if (is_leaf(c)) {
        prefetch_leaf(c);
      } else {
        const char* p = reinterpret_cast<const char*>(&bvh.nodes[size_t(c)]);
        for (uint32_t off = 0; off < sizeof(Bvh8Node); off += 64) simd::prefetch(p + off);
      }
    }
  }

  /// Starts loading leaf `ref`: its size is in the leaf, so the bytes of a typical full leaf
  /// (8 triangles, 10 vertices), from anywhere in a line.
  void prefetch_leaf(int32_t ref) const noexcept {
    const char* p = reinterpret_cast<const char*>(bvh.leaf_data.data() + leaf_offset(ref));
    constexpr uint32_t kBytes = 4 * leaf_words(8, 10);
    for (uint32_t off = 0; off < kBytes; off += 64) simd::prefetch(p + off);
    simd::prefetch(p + kBytes - 1);
  }
};

/// One instance as the traversals read it: the map into its object space and its mesh's tree.
struct Placed {
  Affine3f world_to_object;
  const Bvh8* mesh;
  /// The typical size of a leaf of the mesh's tree as placed, in world units (mean_leaf_size
  /// times the placement's mean scale): large packets use it to judge the rays' density.
  float leaf_size = 0.0f;
};

/// The tree over the instances' world boxes, whose leaf ~i is instance i (placed[i]).
template <class Kernel>
struct InstanceLevel {
  const InstanceTree& tree;
  std::span<const Placed> placed;
  const Scene& scene;

  bool empty() const noexcept { return tree.empty(); }
  const Bvh8Node& node(int32_t ref) const noexcept { return tree.nodes[size_t(ref)]; }
  const Box3f& bounds() const noexcept { return tree.bounds; }
  /// The mesh level of instance i.
  MeshLevel<Kernel> mesh(uint32_t i) const noexcept { return {*placed[i].mesh, scene, i}; }

  /// Starts loading the nodes among the children in `bits` (an instance leaf has no data here).
  void prefetch_children(const Bvh8Node& n, uint32_t bits) const noexcept {
    for (; bits; bits &= bits - 1)
      if (const int32_t c = n.child[std::countr_zero(bits)]; !is_leaf(c))
        for (uint32_t off = 0; off < sizeof(Bvh8Node); off += 64)
          simd::prefetch(reinterpret_cast<const char*>(&tree.nodes[size_t(c)]) + off);
  }
};

template <class Level>
inline constexpr bool kInstanceLevel = false;
template <class Kernel>
inline constexpr bool kInstanceLevel<InstanceLevel<Kernel>> = true;

/// The lanes `mask` of `rays` (at most 8) in an instance's object space (rp::object_ray by
/// `world_to_object`: the single-ray path's bits) as `o[0..8)`; the other lanes an invalid ray.
inline void object_rays(const Affine3f& world_to_object, std::span<const Ray> rays, uint32_t mask, Ray* o) {
  constexpr Ray kInactive{{0.0f, 0.0f, 0.0f}, 1.0f, {1.0f, 1.0f, 1.0f}, 0.0f};  // tnear > tfar: invalid
  for (size_t lane = 0; lane < 8; ++lane)
    o[lane] = (mask >> lane & 1u) ? object_ray(rays[lane], world_to_object) : kInactive;
}

}  // namespace rp::bvh8
