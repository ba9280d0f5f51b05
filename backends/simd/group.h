#pragma once
/// A large packet of the simd backend (large_packet.h) as its loop keeps it: the span's 8-ray
/// packets and their scratch (GroupPacket, GroupWork), the packets grouped by direction
/// octant (Groups), a group's interval-arithmetic beam and each member's (GroupBeam), and the
/// members an entry of the tree carries (RangeEntry in a mesh's tree, MaskEntry in the
/// instance tree), with the tests that narrow them at a node and at a leaf. AVX2+FMA
/// translation units only.

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <limits>
#include <span>

#include "backends/simd/packet.h"
#include "backends/simd/queries.h"

namespace rp::bvh8 {

/// Packets in one large packet: 64 packets, 512 rays.
inline constexpr int kMaxPackets = 64;
/// A range of this many packets or fewer continues as independent 8-ray packets.
inline constexpr int kPacketFallback = 1;
/// An octant with fewer packets than this in a span is traced as 8-ray packets.
inline constexpr int kMinGroupPackets = 2;
/// Rays go through an instance's mesh as a group when neighbouring rays pass it at most this
/// many of the mesh's leaf sizes apart (LargePacketTraversal::dense), else as 8-ray packets.
inline constexpr float kDenseGap = 2.0f;

/// A pushed subtree of a mesh's tree: the node or leaf, the range [first, last] of the
/// group's members that may reach it, and its box (a leaf's box lives in its parent only).
struct RangeEntry {
  int32_t ref;
  uint8_t first, last;
  Vec3f lo, hi;
};

/// A pushed subtree of the instance tree: the members that reach it as bits (bit k: group
/// member k), not a range: over a field of many small instances the members between the first
/// and the last that reach a box mostly miss it, and testing them cost more than the group
/// saved (slower than 8-ray packets on a large field of instances; figures:
/// docs/notes/2026-11-29-figures-from-code-comments.md).
struct MaskEntry {
  int32_t ref;
  uint64_t reach;
  Vec3f lo, hi;
};

/// The entry of each level.
template <class Level>
using GroupEntry = std::conditional_t<kInstanceLevel<Level>, MaskEntry, RangeEntry>;

/// A traversal stack, left uninitialised: only pushed entries are read (zeroing kStackSize
/// boxes per group was a measurable share of the instructions).
template <class Entry>
struct GroupStack {
  union {
    Entry at[kStackSize];
  };
  GroupStack() {}
};

/// One packet of the span and everything the traversals keep for it.
template <class Kernel>
struct GroupPacket {
  RayPacket p;
  typename Kernel::Packet kp;  ///< the triangle test's per-packet data
  bool has_setup = false;      ///< GroupWork::setups holds its 8-ray set-up
  PacketHits h;
  uint32_t active = 0;  ///< valid lanes
  uint32_t live = 0;    ///< lanes still being traced (any hit: not yet occluded)
  int octant = -1;      ///< 0..7 when every active lane has this sign pattern and no 0 component
};

/// The scratch of one span: a thread's own, reused from span to span. The packets' 8-ray
/// set-ups (used only when a packet continues on its own) live apart, so the rays the group
/// traversal reads for every node stay close together in L1.
template <class Kernel>
struct GroupWork {
  std::array<GroupPacket<Kernel>, kMaxPackets> packets;
  std::array<PacketSetup<Kernel>, kMaxPackets> setups;
  int count = 0;
  std::array<Ray, 8 * kMaxPackets> rays;  ///< object-space rays (object_work() only)
};
inline std::span<const Ray> packet_rays(std::span<const Ray> rays, int i) {
  return rays.subspan(size_t(i) * 8, std::min<size_t>(8, rays.size() - size_t(i) * 8));
}

/// The packet's 8-ray traversal set-up, built on first use.
template <class Kernel>
RP_SIMD_INLINE const PacketSetup<Kernel>& setup(GroupWork<Kernel>& w, int i, std::span<const Ray> rays) {
  GroupPacket<Kernel>& q = w.packets[size_t(i)];
  if (!q.has_setup) {
    w.setups[size_t(i)] = PacketSetup<Kernel>(q.p, rays, q.active);
    q.has_setup = true;
  }
  return w.setups[size_t(i)];
}

/// Loads the span's packets; returns their count.
template <class Kernel>
int load(std::span<const Ray> rays, GroupWork<Kernel>& w, bool closest) noexcept {
  const int count = int((rays.size() + 7) / 8);
  const float8 inf(std::numeric_limits<float>::infinity());
  for (int i = 0; i < count; ++i) {
    GroupPacket<Kernel>& q = w.packets[size_t(i)];
    const std::span<const Ray> r = packet_rays(rays, i);
    q.active = load_packet(r, q.p, q.h.tfar);
    q.live = q.active;
    q.octant = -1;
    q.has_setup = false;
    if (closest) q.h.clear();
    if (!q.active) continue;
    q.kp = typename Kernel::Packet(q.p, r);
    // One octant: every active lane has the same sign pattern and no zero component.
    const uint32_t finite =
        simd::movemask((xsimd::abs(q.p.inv.x) < inf) & (xsimd::abs(q.p.inv.y) < inf) & (xsimd::abs(q.p.inv.z) < inf));
    const uint32_t nx = simd::movemask(q.p.neg_x) & q.active, ny = simd::movemask(q.p.neg_y) & q.active,
                   nz = simd::movemask(q.p.neg_z) & q.active;
    const auto uniform = [&](uint32_t n) { return n == 0 || n == q.active; };
    if ((finite & q.active) == q.active && uniform(nx) && uniform(ny) && uniform(nz))
      q.octant = int(nx != 0) | int(ny != 0) << 1 | int(nz != 0) << 2;
  }
  w.count = count;
  return count;
}

/// The packets of each octant with enough of them for a group, in span order; the others go
/// to `single` (traced as 8-ray packets from the root).
struct Groups {
  uint8_t members[8][kMaxPackets];
  int size[8] = {};
  uint8_t single[kMaxPackets];
  int singles = 0;
};
template <class Kernel>
void group_octants(const GroupWork<Kernel>& w, Groups& g) {
  for (int i = 0; i < w.count; ++i) {
    const GroupPacket<Kernel>& q = w.packets[size_t(i)];
    if (!q.active) continue;
    if (q.octant < 0)
      g.single[g.singles++] = uint8_t(i);
    else
      g.members[q.octant][g.size[q.octant]++] = uint8_t(i);
  }
  for (int o = 0; o < 8; ++o)
    if (g.size[o] > 0 && g.size[o] < kMinGroupPackets) {
      for (int k = 0; k < g.size[o]; ++k) g.single[g.singles++] = g.members[o][k];
      g.size[o] = 0;
    }
}

/// What the group shares: its beam, its direction signs (as flags and as +-1 for ordering
/// children), the largest tfar of its rays, and each member's own beam (lane k % 8 of
/// block k / 8 for member k).
template <class Kernel>
struct GroupBeam {
  PacketBeam beam;
  typename Kernel::Beam kbeam;  ///< what the kernel takes of `beam`
  float8 sx, sy, sz;
  float tfar_max;
  PacketBeams8 members[kMaxPackets / 8];
};

/// The beams of the group `members` of one octant and of each member, over their live rays.
template <class Kernel>
void group_beam(const GroupWork<Kernel>& w, const uint8_t* members, int n, int octant, GroupBeam<Kernel>& gb) {
  const bool neg[3] = {(octant & 1) != 0, (octant & 2) != 0, (octant & 4) != 0};
  constexpr float inf = std::numeric_limits<float>::infinity();
  const float8 inf8(inf);
  // Per member: rows omin[3], omax[3], imin[3], imax[3], tnear_min, tfar_max.
  alignas(32) float row[14][kMaxPackets];
  const int blocks = (n + 7) / 8;
  for (int k = 0; k < 8 * blocks; ++k) {
    const GroupPacket<Kernel>* q = k < n ? &w.packets[members[k]] : nullptr;
    if (!q || !q->live) {  // reaches nothing
      for (int r = 0; r < 14; ++r) row[r][k] = r == 12 ? inf : 0.0f;
      continue;
    }
    const mask8 on = simd::mask_from_bits(q->live);
    const float8 org[3] = {q->p.org.x, q->p.org.y, q->p.org.z}, inv[3] = {q->p.inv.x, q->p.inv.y, q->p.inv.z};
    for (int a = 0; a < 3; ++a) {
      const float8 o = neg[a] ? -org[a] : org[a], i = neg[a] ? -inv[a] : inv[a];
      row[a][k] = simd::reduce_min(xsimd::select(on, o, inf8));
      row[3 + a][k] = simd::reduce_max(xsimd::select(on, o, -inf8));
      row[6 + a][k] = simd::reduce_min(xsimd::select(on, i, inf8));
      row[9 + a][k] = simd::reduce_max(xsimd::select(on, i, -inf8));
    }
    row[12][k] = simd::reduce_min(xsimd::select(on, q->p.tnear, inf8));
    row[13][k] = simd::reduce_max(xsimd::select(on, q->h.tfar, float8(0.0f)));
  }
  float8 lo[14], hi[14];
  for (int r = 0; r < 14; ++r) lo[r] = inf8, hi[r] = -inf8;
  for (int blk = 0; blk < blocks; ++blk) {
    PacketBeams8& m = gb.members[blk];
    float8 v[14];
    for (int r = 0; r < 14; ++r) v[r] = float8::load_aligned(&row[r][8 * blk]);
    const mask8 used = v[12] < inf8;  // members with live rays
    for (int r = 0; r < 14; ++r) {
      lo[r] = xsimd::min(lo[r], xsimd::select(used, v[r], inf8));
      hi[r] = xsimd::max(hi[r], xsimd::select(used, v[r], -inf8));
    }
    for (int a = 0; a < 3; ++a) {
      m.omin[a] = v[a];
      m.omax[a] = v[3 + a];
      m.imin[a] = v[6 + a];
      m.imax[a] = v[9 + a];
    }
    m.tnear_min = v[12];
    m.tfar_max = v[13];
  }
  BeamBounds b;
  for (int a = 0; a < 3; ++a) {
    b.omin[a] = simd::reduce_min(lo[a]);
    b.omax[a] = simd::reduce_max(hi[3 + a]);
    b.imin[a] = simd::reduce_min(lo[6 + a]);
    b.imax[a] = simd::reduce_max(hi[9 + a]);
  }
  b.tnear_min = simd::reduce_min(lo[12]);
  gb.beam = PacketBeam(b, neg);
  gb.kbeam = typename Kernel::Beam(gb.beam);
  gb.sx = float8(neg[0] ? -1.0f : 1.0f);
  gb.sy = float8(neg[1] ? -1.0f : 1.0f);
  gb.sz = float8(neg[2] ? -1.0f : 1.0f);
  gb.tfar_max = simd::reduce_max(hi[13]);
}

/// Members in [first, last] whose beam may reach box [lo, hi], as bits.
template <class Kernel>
RP_SIMD_INLINE uint64_t beam_hits(const GroupBeam<Kernel>& gb, const Vec3f& lo, const Vec3f& hi, int first, int last) {
  uint64_t maybe = 0;
  for (int blk = first / 8; blk <= last / 8; ++blk)
    maybe |= uint64_t(gb.members[blk].cull(gb.beam.neg, lo, hi)) << (8 * blk);
  const uint64_t upto_last = last >= 63 ? ~uint64_t(0) : (uint64_t(1) << (last + 1)) - 1;
  return maybe & upto_last & ~((uint64_t(1) << first) - 1);
}

/// Narrows [first, last] to the first and the last member whose live lanes hit box [lo, hi]
/// (an 8-ray slab test each, only for members whose beam may reach the box); first > last
/// when none does.
template <class Kernel>
RP_SIMD_INLINE void bound_range(const GroupWork<Kernel>& w, const uint8_t* members, const GroupBeam<Kernel>& gb,
                                const Vec3f& lo, const Vec3f& hi, int& first, int& last) {
  uint64_t maybe = beam_hits(gb, lo, hi, first, last);
  auto hits = [&](int k) {
    const GroupPacket<Kernel>& q = w.packets[members[k]];
    return (intersect_box_octant(q.p, gb.beam.neg, lo, hi, q.h.tfar) & q.live) != 0;
  };
  for (; maybe; maybe &= maybe - 1)
    if (hits(std::countr_zero(maybe))) break;
  if (!maybe) {
    first = last + 1;
    return;
  }
  first = std::countr_zero(maybe);
  for (maybe &= maybe - 1; maybe; maybe &= ~(uint64_t(1) << (63 - std::countl_zero(maybe))))
    if (hits(63 - std::countl_zero(maybe))) break;
  last = maybe ? 63 - std::countl_zero(maybe) : first;
}

/// Pushes the children of node `n` that the members of entry `e` may reach, nearest last.
/// `e` may be the stack's slot `sp` (the entry just popped): it is read before any push.
/// The kids are sorted as slot numbers and ranges, and each entry written to the stack a
/// field at a time: entries built whole and copied were read back 16 bytes at a time from
/// 4-byte stores, which no store can forward.
template <class Kernel>
void push_children(const GroupWork<Kernel>& w, const uint8_t* members, const GroupBeam<Kernel>& gb, const Bvh8Node& n,
                   const RangeEntry& e, RangeEntry* stack, int& sp) {
  const int e_first = e.first, e_last = e.last;
  const uint32_t candidates = gb.beam.cull(n, gb.tfar_max);
  if (!candidates) return;
  alignas(32) float key[8];
  near_first_keys(n, gb.sx, gb.sy, gb.sz).store_aligned(key);
  uint8_t kid[8], kid_first[8], kid_last[8];
  float kid_key[8];
  int k = 0;
  for (uint32_t bits = candidates; bits; bits &= bits - 1) {
    const int c = std::countr_zero(bits);
    if (n.child[c] == kEmpty) continue;
    const Vec3f lo{n.lo_x[c], n.lo_y[c], n.lo_z[c]}, hi{n.hi_x[c], n.hi_y[c], n.hi_z[c]};
    int first = e_first, last = e_last;
    bound_range(w, members, gb, lo, hi, first, last);
    if (first > last) continue;
    int j = k++;
    for (; j > 0 && kid_key[j - 1] < key[c]; --j) {  // descending keys: the nearest ends up last
      kid[j] = kid[j - 1];
      kid_first[j] = kid_first[j - 1];
      kid_last[j] = kid_last[j - 1];
      kid_key[j] = kid_key[j - 1];
    }
    kid[j] = uint8_t(c);
    kid_first[j] = uint8_t(first);
    kid_last[j] = uint8_t(last);
    kid_key[j] = key[c];
  }
  RP_DCHECK(sp + k <= kStackSize);
  for (int j = 0; j < k; ++j) {
    RangeEntry& to = stack[sp++];
    const int c = kid[j];
    to.ref = n.child[c];
    to.first = kid_first[j];
    to.last = kid_last[j];
    to.lo = {n.lo_x[c], n.lo_y[c], n.lo_z[c]};
    to.hi = {n.hi_x[c], n.hi_y[c], n.hi_z[c]};
  }
}

/// The members of entry `e` (a leaf) whose live lanes hit its box, and those lanes.
template <class Kernel>
RP_SIMD_INLINE int leaf_packets(const GroupWork<Kernel>& w, const uint8_t* members, const GroupBeam<Kernel>& gb,
                                const RangeEntry& e, uint8_t* which, uint32_t* lanes) {
  int m = 0;
  for (uint64_t maybe = beam_hits(gb, e.lo, e.hi, e.first, e.last); maybe; maybe &= maybe - 1) {
    const int k = std::countr_zero(maybe);
    const GroupPacket<Kernel>& q = w.packets[members[k]];
    if (!q.live) continue;
    const uint32_t hit = intersect_box_octant(q.p, gb.beam.neg, e.lo, e.hi, q.h.tfar) & q.live;
    if (!hit) continue;
    which[m] = members[k];
    lanes[m++] = hit;
  }
  return m;
}

/// Of the m packets `which` (lanes `lanes` there) that reach a leaf of `count` triangles,
/// hands those with few lanes there (Traversal::by_rays) to f(packet, lanes), which tests
/// them a lane at a time, and keeps the others for the triangle-at-a-time test; returns
/// how many it kept.
template <class F>
RP_SIMD_INLINE int split_by_rays(uint8_t* which, uint32_t* lanes, int m, uint32_t count, F&& f) {
  int kept = 0;
  for (int j = 0; j < m; ++j) {
    if (by_rays(lanes[j], count)) {
      f(which[j], lanes[j]);
    } else {
      which[kept] = which[j];
      lanes[kept++] = lanes[j];
    }
  }
  return kept;
}

/// Whether the rays of the m members `which` (lanes `lanes`) reaching an instance whose box
/// is centred at `at` are dense enough there for a group to pay in its mesh's tree: the
/// distance between the first two rays of one packet (neighbours in a tile) where they pass
/// `at` is at most kDenseGap times the typical leaf size of the mesh as placed. Measured on
/// primary rays: where the gap is below a leaf size (a few instances filling the image)
/// groups beat 8-ray packets; where it is many leaf sizes (a large field of small instances,
/// a few packets reaching each) groups lose (figures:
/// docs/notes/2026-11-29-figures-from-code-comments.md).
template <class Kernel>
bool dense(const GroupWork<Kernel>& w, const uint8_t* which, const uint32_t* lanes, int m, const Vec3f& at,
           float leaf_size) {
  for (int j = 0; j < m; ++j) {
    if (std::popcount(lanes[j]) < 2) continue;
    const int a = std::countr_zero(lanes[j]), b = std::countr_zero(lanes[j] & (lanes[j] - 1));
    const GroupPacket<Kernel>& q = w.packets[which[j]];
    alignas(32) float v[6][8];
    q.p.org.x.store_aligned(v[0]);
    q.p.org.y.store_aligned(v[1]);
    q.p.org.z.store_aligned(v[2]);
    q.p.dir.x.store_aligned(v[3]);
    q.p.dir.y.store_aligned(v[4]);
    q.p.dir.z.store_aligned(v[5]);
    const Vec3f oa{v[0][a], v[1][a], v[2][a]}, ob{v[0][b], v[1][b], v[2][b]};
    const Vec3f da{v[3][a], v[4][a], v[5][a]}, db{v[3][b], v[4][b], v[5][b]};
    const float t = std::max(0.0f, dot(at - oa, da) / dot(da, da));
    const Vec3f gap = (ob + db * t) - (oa + da * t);
    return kDenseGap * kDenseGap * leaf_size * leaf_size >= dot(gap, gap);
  }
  return false;
}

}  // namespace rp::bvh8
