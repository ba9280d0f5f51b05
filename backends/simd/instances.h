#pragma once
/// The instance level of the simd backend's two-level structure: an 8-wide tree over the
/// instances' world boxes (InstanceTree, bvh8.h) above the instanced meshes' own trees, each
/// built once in its object space however many instances place it. AVX2+FMA translation
/// units only.
///
/// A ray goes down the instance tree in world space; at an instance it is taken into the
/// instance's object space by rp::object_ray (engine/affine.h: the origin and direction mapped
/// by Instance::world_to_object, the direction not renormalised, so t stays the world t), and
/// traced through the mesh's tree by that tree's Traversal with the instance's id: the hits
/// of all instances and of the world's tree meet in one Hit (or PacketHits) under the one
/// closest-hit rule, the least (t, prim_id, instance_id) (traversal.h). An instance is traced
/// only for rays whose object-space image obeys the valid-ray rule (engine/ray.h), which keeps
/// the kernels within the range where they cannot overflow; any other ray misses that
/// instance, on every backend and in the reference (README, "Hit convention").
///
/// Single rays and 8-ray packets have their own instance traversal here. A packet stays a
/// packet under an affine map: at an instance its live lanes are mapped one by one (the same
/// function, so the same bits as a single ray's) and loaded as an 8-ray packet of the mesh's
/// tree. Large packets (large_packet.h) and ray streams (stream.h) go down the instance tree
/// as groups and streams, and continue through each instance's mesh as a large packet or a
/// stream of their own; they read the tree and the placements through InstanceQueries.

#include <bit>
#include <cmath>
#include <span>
#include <vector>

#include "backends/simd/traversal.h"
#include "engine/affine.h"

namespace rp::bvh8 {

template <class Kernel>
class InstanceTraversal final : public InstanceQueries<Kernel> {
 public:
  using Placed = typename InstanceQueries<Kernel>::Placed;

  /// `placed[i]` for instance i of the scene (ids of InstanceTree's leaves).
  InstanceTraversal(const InstanceTree& tree, std::vector<Placed> placed) : tree_(tree), placed_(std::move(placed)) {}

  const InstanceTree& tree() const noexcept override { return tree_; }
  const Placed& placed(uint32_t i) const noexcept override { return placed_[i]; }

  // ---- single rays ----

  /// Takes any closer hit of valid ray `r` among the instances into `best` (by the closest-hit
  /// rule, so at an equal t too).
  void closest(const Ray& r, Hit& best) const noexcept override {
    if (!tree_.empty()) closest(r, SingleRay(r), 0, best);
  }

  /// The same from node `root` of the instance tree, for a ray set up already.
  void closest(const Ray& r, const SingleRay& sr, int32_t root, Hit& best) const noexcept override {
    DistanceEntry stack[kStackSize];
    int sp = 0;
    int32_t ref = root;
    for (;;) {
      if (!is_leaf(ref)) {
        const Bvh8Node& n = tree_.nodes[size_t(ref)];
        float8 t_enter;
        if (const uint32_t bits = intersect_node(n, sr, r.tnear, std::min(r.tfar, best.t), t_enter)) {
          alignas(32) float dist[8];
          t_enter.store_aligned(dist);
          ref = push_near_first(n, bits, dist, stack, sp);
          continue;
        }
      } else {
        const uint32_t i = leaf_offset(ref);
        const Placed& in = placed_[i];
        const Ray o = object_ray(r, in.world_to_object);
        if (valid_ray(o) && !in.mesh->bvh().empty()) in.mesh->closest(o, 0, best, i);
      }
      for (;;) {  // pop, skipping instances entered beyond the current hit (padded as intersect_node)
        if (sp == 0) return;
        const DistanceEntry e = stack[--sp];
        if (e.t <= std::fma(std::min(r.tfar, best.t), kSlabPad, sr.pad)) {
          ref = e.ref;
          break;
        }
      }
    }
  }

  /// True when some instance occludes valid ray `r` within [tnear, tfar].
  bool any(const Ray& r) const noexcept override { return !tree_.empty() && any(r, SingleRay(r), 0); }

  /// The same from node `root`, for a ray set up already.
  bool any(const Ray& r, const SingleRay& sr, int32_t root) const noexcept override {
    int32_t stack[kStackSize];
    stack[0] = root;
    int sp = 1;
    while (sp > 0) {
      const int32_t ref = stack[--sp];
      if (!is_leaf(ref)) {
        float8 t_enter;
        RP_DCHECK(sp + 8 <= kStackSize);
        for (uint32_t bits = intersect_node(tree_.nodes[size_t(ref)], sr, r.tnear, r.tfar, t_enter); bits;
             bits &= bits - 1)
          stack[sp++] = tree_.nodes[size_t(ref)].child[std::countr_zero(bits)];
        continue;
      }
      const Placed& in = placed_[leaf_offset(ref)];
      const Ray o = object_ray(r, in.world_to_object);
      if (valid_ray(o) && !in.mesh->bvh().empty() && in.mesh->any(o, 0)) return true;
    }
    return false;
  }

  // ---- 8-ray packets ----

  /// Takes closer hits of the lanes of `mask` of packet `p` (the world rays `rays`, set up in
  /// `ps`) among the instances of subtree `root` into `h`. Below kSingleRayLanes live lanes an
  /// entry's rays continue one at a time.
  void closest_packet(int32_t root, uint32_t mask, const RayPacket& p, const PacketSetup<Kernel>& ps,
                      std::span<const Ray> rays, PacketHits& h) const noexcept override {
    if (tree_.empty()) return;
    using Entry = typename Traversal<Kernel>::PacketEntry;
    Entry stack[kStackSize];
    stack[0] = {root, mask};
    int sp = 1;
    while (sp > 0) {
      const Entry e = stack[--sp];
      if (simd::lane_count(e.mask) <= kSingleRayLanes) {
        h.each_lane(e.mask, [&](int lane, Hit& hit) {
          const Ray& r = rays[size_t(lane)];
          closest(r, SingleRay(r), e.ref, hit);
        });
        continue;
      }
      if (!is_leaf(e.ref)) {
        typename Traversal<Kernel>::Child kids[8];
        const int k = Traversal<Kernel>::ordered_children(tree_.nodes[size_t(e.ref)], p, ps, h.tfar, e.mask, kids);
        RP_DCHECK(sp + k <= kStackSize);
        for (int j = 0; j < k; ++j) stack[sp++] = {kids[j].ref, kids[j].mask};
        continue;
      }
      const uint32_t i = leaf_offset(e.ref);
      const Placed& in = placed_[i];
      if (in.mesh->bvh().empty()) continue;
      Ray o[8];
      RayPacket op;
      float8 tfar;
      const uint32_t valid = to_object(in, rays, e.mask, o, op, tfar);
      if (simd::lane_count(valid) <= kSingleRayLanes) {
        h.each_lane(valid, [&](int lane, Hit& hit) { in.mesh->closest(o[lane], 0, hit, i); });
      } else {
        in.mesh->closest_packet(0, valid, op, PacketSetup<Kernel>(op, o, valid), o, h, i);
      }
    }
  }

  /// The lanes of `live` of packet `p` that some instance of subtree `root` occludes (tfar per
  /// lane).
  uint32_t any_packet(int32_t root, uint32_t live, const RayPacket& p, const PacketSetup<Kernel>& ps,
                      std::span<const Ray> rays, const float8& tfar) const noexcept override {
    if (tree_.empty()) return 0;
    using Entry = typename Traversal<Kernel>::PacketEntry;
    Entry stack[kStackSize];
    stack[0] = {root, live};
    int sp = 1;
    uint32_t done = 0;
    while (sp > 0 && live & ~done) {
      Entry e = stack[--sp];
      e.mask &= ~done;
      if (!e.mask) continue;
      if (simd::lane_count(e.mask) <= kSingleRayLanes) {
        for (uint32_t b = e.mask; b; b &= b - 1) {
          const Ray& r = rays[size_t(std::countr_zero(b))];
          if (any(r, SingleRay(r), e.ref)) done |= b & (~b + 1);
        }
        continue;
      }
      if (!is_leaf(e.ref)) {
        typename Traversal<Kernel>::Child kids[8];
        const int k = Traversal<Kernel>::ordered_children(tree_.nodes[size_t(e.ref)], p, ps, tfar, e.mask, kids);
        RP_DCHECK(sp + k <= kStackSize);
        for (int j = 0; j < k; ++j) stack[sp++] = {kids[j].ref, kids[j].mask};
        continue;
      }
      const Placed& in = placed_[leaf_offset(e.ref)];
      if (in.mesh->bvh().empty()) continue;
      Ray o[8];
      RayPacket op;
      float8 otfar;
      const uint32_t valid = to_object(in, rays, e.mask, o, op, otfar);
      if (simd::lane_count(valid) <= kSingleRayLanes) {
        for (uint32_t b = valid; b; b &= b - 1)
          if (in.mesh->any(o[std::countr_zero(b)], 0)) done |= b & (~b + 1);
      } else if (valid) {
        done |= in.mesh->any_packet(0, valid, op, PacketSetup<Kernel>(op, o, valid), o, otfar);
      }
    }
    return done;
  }

 private:
  /// The lanes `mask` of `rays` in the object space of `in`, as rays `o` (rp::object_ray, the
  /// single-ray path's bits) and as a packet `op` with their tfar; returns the lanes whose
  /// object-space ray is valid (the others miss the instance).
  static uint32_t to_object(const Placed& in, std::span<const Ray> rays, uint32_t mask, Ray o[8], RayPacket& op,
                            float8& tfar) {
    object_rays(in.world_to_object, rays, mask, o);
    return load_packet(std::span<const Ray>(o, 8), op, tfar) & mask;
  }

  const InstanceTree& tree_;
  std::vector<Placed> placed_;
};

}  // namespace rp::bvh8
