#pragma once
/// The simd backend's queries of a whole scene by single rays and 8-ray packets: the world's
/// tree (a MeshLevel), then the instance tree (an InstanceLevel) when the scene has instances,
/// then the unbounded planes. The loops are single_ray.h and packet8.h; the large-packet and
/// stream shapes (large_packet.h, stream.h) take the levels from here. AVX2+FMA translation
/// units only.

#include <limits>
#include <span>

#include "backends/simd/packet8.h"

namespace rp::bvh8 {

template <class Kernel>
class Traversal {
 public:
  /// The traversal of the world's tree `bvh` of `scene`, and of its instances `placed`
  /// (instance i: placed[i]) under `tree` when the scene has any.
  Traversal(const Bvh8& bvh, const Scene& scene, const InstanceTree& tree = kNoTree,
            std::span<const Placed> placed = {})
      : world_{bvh, scene, kNoInstance},
        scene_(scene),
        instances_{tree, placed, scene},
        has_instances_(!tree.empty()) {}

  const MeshLevel<Kernel>& world() const { return world_; }
  /// The instance level, or null when the scene has no instances.
  const InstanceLevel<Kernel>* instances() const { return has_instances_ ? &instances_ : nullptr; }
  const Scene& scene() const { return scene_; }

  /// Valid ray `r` through the world's tree, then the instances, answering single-ray query
  /// `q` (queries.h); planes excluded.
  template <class Q>
  void single(const Ray& r, Q& q) const noexcept {
    const SingleRay sr(r);
    if (!world_.empty()) trace_single<Kernel>(world_, r, sr, 0, q);
    if (!q.done() && has_instances_) trace_single<Kernel>(instances_, r, sr, 0, q);
  }

  /// Closest hit of one ray (a miss for an invalid one), the instances and planes included.
  Hit intersect_single(const Ray& r) const noexcept {
    Hit best;
    if (!valid_ray(r)) return best;
    ClosestSingle<Kernel> q(r, best);
    single(r, q);
    scene_.intersect_planes(r, best);
    return best;
  }

  /// Any hit of one valid ray, the instances and planes included; stops at the first.
  bool occluded_single(const Ray& r) const noexcept {
    if (scene_.occluded_by_planes(r)) return true;
    AnySingle<Kernel> q(r);
    single(r, q);
    return q.found;
  }

  /// Closest hits of up to 8 rays as one packet, the instances and planes included.
  void intersect_packet(std::span<const Ray> rays, std::span<Hit> hits) const noexcept {
    RayPacket p;
    PacketHits h;
    const uint32_t active = load_packet(rays, p, h.tfar);
    h.clear();
    if (active && (!world_.empty() || has_instances_)) {
      const PacketSetup<Kernel> ps(p, rays, active);
      ClosestPacket<Kernel> q{h};
      if (!world_.empty()) trace_packet(world_, 0, active, p, ps, rays, q);
      if (has_instances_) trace_packet(instances_, 0, active, p, ps, rays, q);
    }
    store_hits(rays, active, h, hits);
  }

  /// Any hits of up to 8 rays as one packet, the instances and planes included.
  void occluded_packet(std::span<const Ray> rays, std::span<uint8_t> out) const noexcept {
    RayPacket p;
    float8 tfar;
    const uint32_t active = load_packet(rays, p, tfar);
    uint32_t done = 0;
    for (uint32_t b = active; b; b &= b - 1) {
      const int lane = std::countr_zero(b);
      if (scene_.occluded_by_planes(rays[size_t(lane)])) done |= 1u << lane;
    }
    const uint32_t live = active & ~done;
    if (live && (!world_.empty() || has_instances_)) {
      const PacketSetup<Kernel> ps(p, rays, live);
      AnyPacket<Kernel> q(tfar, live);
      if (!world_.empty()) trace_packet(world_, 0, live, p, ps, rays, q);
      if (has_instances_ && q.live()) trace_packet(instances_, 0, live & ~q.done, p, ps, rays, q);
      done |= q.done;
    }
    for (size_t i = 0; i < rays.size(); ++i) out[i] = uint8_t(done >> i & 1u);
  }

  /// Writes the hits of a packet's rays, field by field (no 16-byte reload of a Hit built in
  /// pieces), and lets the unbounded planes take the hits of its active lanes.
  void store_hits(std::span<const Ray> rays, uint32_t active, const PacketHits& h, std::span<Hit> hits) const noexcept {
    const simd::Spill<3> s(h.tfar, h.u, h.v);
    const auto& [tf, uu, vv] = s.lanes;
    for (size_t i = 0; i < rays.size(); ++i) {
      Hit& out = hits[i];
      const bool hit = h.prim[i] != kInvalidId;  // an inactive lane never gets a primitive
      out.t = hit ? tf[i] : std::numeric_limits<float>::infinity();
      out.prim_id = h.prim[i];
      out.u = hit ? uu[i] : 0.0f;
      out.v = hit ? vv[i] : 0.0f;
      out.instance_id = h.inst[i];
      if (active >> i & 1u) scene_.intersect_planes(rays[i], out);
    }
  }

 private:
  MeshLevel<Kernel> world_;
  const Scene& scene_;
  static inline const InstanceTree kNoTree{};
  InstanceLevel<Kernel> instances_;
  bool has_instances_;
};

}  // namespace rp::bvh8
