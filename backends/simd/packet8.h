#pragma once
/// The 8-ray packet loop of the simd backend: 8 rays against one node's boxes at a time, any
/// level (levels.h), any query (queries.h), from any subtree, so the large-packet shape can
/// hand it the packets it no longer traces as a group. Children are visited near-first along
/// the packet's direction signs; an entry with few live lanes continues as single rays
/// (single_ray.h). AVX2+FMA translation units only.

#include <bit>
#include <span>

#include "backends/simd/queries.h"
#include "backends/simd/single_ray.h"

namespace rp::bvh8 {

/// A subtree an 8-ray packet still has to visit, with the lanes that reach it.
struct PacketEntry {
  int32_t ref;
  uint32_t mask;
};

/// A child of a node that some lane of a packet hits: the lanes, and its near-first key.
struct PacketChild {
  int32_t ref;
  uint32_t mask;
  float key;
};

/// Children of `n` hit by any lane of `mask`, ordered near-first along the packet's direction
/// signs (near_first_keys) into `out`: the nearest ends up last. Returns how many.
template <class Kernel>
int ordered_children(const Bvh8Node& n, const RayPacket& p, const PacketSetup<Kernel>& ps, const float8& tfar,
                     uint32_t mask, PacketChild* out) {
  const PacketBeam& beam = ps.beam;
  uint32_t candidates = 0xffu;
  if (beam.valid)
    candidates = beam.cull(n, simd::reduce_max(xsimd::select(simd::mask_from_bits(mask), tfar, float8(0.0f))));
  alignas(32) float key[8];
  near_first_keys(n, ps.sx, ps.sy, ps.sz).store_aligned(key);
  int k = 0;
  for (int c = 0; c < 8 && n.child[c] != kEmpty; ++c) {
    if (!(candidates >> c & 1u)) continue;
    const Vec3f lo{n.lo_x[c], n.lo_y[c], n.lo_z[c]}, hi{n.hi_x[c], n.hi_y[c], n.hi_z[c]};
    const uint32_t m =
        (beam.valid ? intersect_box_octant(p, beam.neg, lo, hi, tfar) : intersect_box(p, lo, hi, tfar)) & mask;
    if (!m) continue;
    PacketChild e{n.child[c], m, key[c]};
    int j = k++;
    for (; j > 0 && out[j - 1].key < e.key; --j) out[j] = out[j - 1];  // descending: nearest last
    out[j] = e;
  }
  return k;
}

template <class Kernel, class Q>
void packet_leaf(const MeshLevel<Kernel>& lv, int32_t ref, uint32_t mask, const RayPacket& p,
                 const PacketSetup<Kernel>& ps, std::span<const Ray> rays, Q& q);
template <class Kernel, class Q>
void packet_leaf(const InstanceLevel<Kernel>& lv, int32_t ref, uint32_t mask, const RayPacket& p,
                 const PacketSetup<Kernel>& ps, std::span<const Ray> rays, Q& q);

/// The lanes `mask` of packet `p` (the rays `rays`, set up in `ps`) through the subtree `root`
/// of level `lv`, answering query `q`. Below kSingleRayLanes live lanes an entry's rays
/// continue one at a time: a packet whose rays have drifted apart costs 8 lanes of work per
/// box and triangle for one or two useful ones (Benthin et al., "Combining Single and
/// Packet-Ray Tracing for Arbitrary Ray Distributions on the Intel MIC Architecture", IEEE
/// TVCG 18(9), 2012).
template <class Kernel, class Level, class Q>
void trace_packet(const Level& lv, int32_t root, uint32_t mask, const RayPacket& p, const PacketSetup<Kernel>& ps,
                  std::span<const Ray> rays, Q& q) noexcept {
  PacketEntry stack[kStackSize];
  stack[0] = {root, mask};
  int sp = 1;
  while (sp > 0 && q.live()) {
    PacketEntry e = stack[--sp];
    e.mask = q.pending(e.mask);
    if (!e.mask) continue;
    if (simd::lane_count(e.mask) <= kSingleRayLanes) {
      q.each_single(e.mask, rays, [&](const Ray& r, auto& s) { trace_single<Kernel>(lv, r, SingleRay(r), e.ref, s); });
      continue;
    }
    if (!is_leaf(e.ref)) {
      PacketChild kids[8];
      const int k = ordered_children(lv.node(e.ref), p, ps, q.tfar(), e.mask, kids);
      RP_DCHECK(sp + k <= kStackSize);
      for (int j = 0; j < k; ++j) stack[sp++] = {kids[j].ref, kids[j].mask};
      continue;
    }
    packet_leaf(lv, e.ref, e.mask, p, ps, rays, q);
  }
}

/// The primitives of leaf `ref` against the lanes of `mask`.
template <class Kernel, class Q>
void packet_leaf(const MeshLevel<Kernel>& lv, int32_t ref, uint32_t mask, const RayPacket& p,
                 const PacketSetup<Kernel>& ps, std::span<const Ray> rays, Q& q) {
  const Leaf leaf = lv.bvh.leaf(ref);
  if (const uint32_t id = lv.analytic_leaf(leaf); id != kInvalidId) {
    q.analytic(lv.scene, id, rays, mask);
    return;
  }
  q.triangles(leaf, mask, p, ps, rays, lv.inst);
}

/// An instance: a packet stays a packet under an affine map, so its lanes `mask` are mapped
/// one by one (the single-ray path's bits) and loaded as an 8-ray packet of the mesh's tree.
template <class Kernel, class Q>
void packet_leaf(const InstanceLevel<Kernel>& lv, int32_t ref, uint32_t mask, const RayPacket&,
                 const PacketSetup<Kernel>&, std::span<const Ray> rays, Q& q) {
  const uint32_t i = leaf_offset(ref);
  const Placed& in = lv.placed[i];
  if (in.mesh->empty()) return;
  Ray o[8];
  RayPacket op;
  float8 tfar;
  object_rays(in.world_to_object, rays, mask, o);
  const std::span<const Ray> orays(o, 8);
  const uint32_t valid = load_packet(orays, op, tfar) & mask;  // the others miss the instance
  const MeshLevel<Kernel> mesh = lv.mesh(i);
  if (simd::lane_count(valid) <= kSingleRayLanes) {
    q.each_single(valid, orays, [&](const Ray& r, auto& s) { trace_single<Kernel>(mesh, r, SingleRay(r), 0, s); });
    return;
  }
  decltype(auto) sub = q.object(valid, tfar);
  trace_packet(mesh, 0, valid, op, PacketSetup<Kernel>(op, orays, valid), orays, sub);
  q.join(sub);
}

}  // namespace rp::bvh8
