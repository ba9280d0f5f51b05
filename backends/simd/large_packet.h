#pragma once
/// Large-packet traversal for coherent spans (a renderer's tile, a bench's primary or shadow
/// rays): up to kMaxPackets 8-ray packets that share a direction octant traverse the tree as
/// one group, so a node is fetched and culled once for the whole group instead of once per
/// packet, and a leaf's triangles are set up once for every packet that reaches it. AVX2+FMA
/// translation units only.
///
/// Per inner node (Wald, Boulos and Shirley, "Ray Tracing Deformable Scenes using Dynamic
/// Bounding Volume Hierarchies", ACM TOG 26(1), 2007; Boulos, Wald and Shirley, "Geometric
/// and Arithmetic Culling Methods for Entire Ray Packets", 2006):
/// 1. the group's interval-arithmetic beam (the bounds of all its rays' origins and inverse
///    directions) culls the 8 children in one 8-wide step;
/// 2. for each surviving child, the first and the last packet of the entry's range whose rays
///    hit the child's box (an 8-ray slab test each) bound the range the child is pushed
///    with, or cull it when there is none: partition traversal (Overbeck, Ramamoorthi and
///    Mark, "Large Ray Packets for Real-time Whitted Ray Tracing", IEEE RT 2008);
/// 3. children are pushed near-first along the group's direction signs.
/// At a leaf each packet of the range is tested against the leaf's box; then each triangle is
/// set up once (broadcast, and for Möller–Trumbore its normal) and tested against every
/// packet that reached the leaf. A range of kPacketFallback packets or fewer continues as
/// 8-ray packets (Traversal::closest_packet), which in turn hand entries with few live lanes
/// to single rays; packets whose rays do not share an octant, or have a zero direction
/// component, and octants with fewer than kMinGroupPackets packets, are traced as 8-ray
/// packets from the root.
///
/// In a scene with instances the same groups then go down the instance tree (instances.h)
/// with their beam and near-first order, the members that reach each subtree kept as bits
/// (not a range: see MaskEntry). At an instance,
/// the members whose rays reach its box are mapped into its object space (rp::object_ray per
/// lane, the single-ray path's bits), regrouped by their object-space octants and traced
/// through the mesh's tree as a large packet of their own, sharing the world packets' hits
/// (the map keeps t the world t). So a group fetches each instance's nodes and sets up each
/// of its triangles once, as in a flat scene, instead of once per 8-ray packet. Hits are
/// resolved by the same rule as the other paths (see Traversal), so every answer is theirs,
/// bit for bit.

#include <algorithm>
#include <array>
#include <bit>
#include <limits>
#include <span>

#include "backends/simd/traversal.h"

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

template <class Kernel>
class LargePacketTraversal {
 public:
  explicit LargePacketTraversal(const Traversal<Kernel>& t) : t_(t) {}

  /// Closest hits of a coherent span, cut into large packets of at most kMaxPackets packets.
  void intersect(std::span<const Ray> rays, std::span<Hit> hits) const noexcept {
    for (size_t base = 0; base < rays.size(); base += 8 * kMaxPackets) {
      const size_t n = std::min<size_t>(8 * kMaxPackets, rays.size() - base);
      intersect_span(rays.subspan(base, n), hits.subspan(base, n));
    }
  }

  /// Any hits of a coherent span, cut as intersect() does.
  void occluded(std::span<const Ray> rays, std::span<uint8_t> out) const noexcept {
    for (size_t base = 0; base < rays.size(); base += 8 * kMaxPackets) {
      const size_t n = std::min<size_t>(8 * kMaxPackets, rays.size() - base);
      occluded_span(rays.subspan(base, n), out.subspan(base, n));
    }
  }

 private:
  /// One packet of the span and everything the traversals keep for it.
  struct Packet {
    RayPacket p;
    typename Kernel::Packet kp;  ///< the triangle test's per-packet data
    bool has_setup = false;      ///< Work::setups holds its 8-ray set-up
    PacketHits h;
    uint32_t active = 0;  ///< valid lanes
    uint32_t live = 0;    ///< lanes still being traced (any hit: not yet occluded)
    int octant = -1;      ///< 0..7 when every active lane has this sign pattern and no 0 component
  };

  /// The scratch of one span: a thread's own, reused from span to span. The packets' 8-ray
  /// set-ups (used only when a packet continues on its own) live apart, so the rays the group
  /// traversal reads for every node stay close together in L1.
  struct Work {
    std::array<Packet, kMaxPackets> packets;
    std::array<PacketSetup<Kernel>, kMaxPackets> setups;
    int count = 0;
    std::array<Ray, 8 * kMaxPackets> rays;  ///< object-space rays (object_work() only)
  };
  static Work& work() {
    static thread_local Work w;
    return w;
  }
  /// The scratch of the members of a group at one instance, in its object space.
  static Work& object_work() {
    static thread_local Work w;
    return w;
  }

  static std::span<const Ray> packet_rays(std::span<const Ray> rays, int i) {
    return rays.subspan(size_t(i) * 8, std::min<size_t>(8, rays.size() - size_t(i) * 8));
  }

  /// The packet's 8-ray traversal set-up, built on first use.
  static const PacketSetup<Kernel>& setup(Work& w, int i, std::span<const Ray> rays) {
    Packet& q = w.packets[size_t(i)];
    if (!q.has_setup) {
      w.setups[size_t(i)] = PacketSetup<Kernel>(q.p, rays, q.active);
      q.has_setup = true;
    }
    return w.setups[size_t(i)];
  }

  /// Loads the span's packets; returns their count.
  int load(std::span<const Ray> rays, Work& w, bool closest) const noexcept {
    const int count = int((rays.size() + 7) / 8);
    const float8 inf(std::numeric_limits<float>::infinity());
    for (int i = 0; i < count; ++i) {
      Packet& q = w.packets[size_t(i)];
      const std::span<const Ray> r = packet_rays(rays, i);
      q.active = load_packet(r, q.p, q.h.tfar);
      q.live = q.active;
      q.octant = -1;
      q.has_setup = false;
      if (closest) q.h.clear();
      if (!q.active) continue;
      q.kp = typename Kernel::Packet(q.p, r);
      // One octant: every active lane has the same sign pattern and no zero component.
      const uint32_t finite = simd::movemask((xsimd::abs(q.p.inv.x) < inf) & (xsimd::abs(q.p.inv.y) < inf) &
                                             (xsimd::abs(q.p.inv.z) < inf));
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
  static void group(const Work& w, Groups& g) {
    for (int i = 0; i < w.count; ++i) {
      const Packet& q = w.packets[size_t(i)];
      if (!q.active) continue;
      if (q.octant < 0) g.single[g.singles++] = uint8_t(i);
      else g.members[q.octant][g.size[q.octant]++] = uint8_t(i);
    }
    for (int o = 0; o < 8; ++o)
      if (g.size[o] > 0 && g.size[o] < kMinGroupPackets) {
        for (int k = 0; k < g.size[o]; ++k) g.single[g.singles++] = g.members[o][k];
        g.size[o] = 0;
      }
  }

  void intersect_span(std::span<const Ray> rays, std::span<Hit> hits) const noexcept {
    Work& w = work();
    const int count = load(rays, w, true);
    const InstanceQueries<Kernel>* in = t_.instances();
    if (in && in->tree().empty()) in = nullptr;
    if (!t_.bvh().empty() || in) {
      Groups g;
      group(w, g);
      if (!t_.bvh().empty()) {
        for (int o = 0; o < 8; ++o)
          if (g.size[o] > 0) closest_group(rays, w, g.members[o], g.size[o], o, kNoInstance);
        for (int k = 0; k < g.singles; ++k) {
          Packet& q = w.packets[g.single[k]];
          const std::span<const Ray> r = packet_rays(rays, g.single[k]);
          t_.closest_packet(0, q.active, q.p, setup(w, g.single[k], r), r, q.h);
        }
      }
      if (in) {  // then the same groups through the instances
        for (int o = 0; o < 8; ++o)
          if (g.size[o] > 0) closest_instances(*in, rays, w, g.members[o], g.size[o], o);
        for (int k = 0; k < g.singles; ++k) {
          Packet& q = w.packets[g.single[k]];
          const std::span<const Ray> r = packet_rays(rays, g.single[k]);
          in->closest_packet(0, q.active, q.p, setup(w, g.single[k], r), r, q.h);
        }
      }
    }
    for (int i = 0; i < count; ++i) {
      const Packet& q = w.packets[size_t(i)];
      t_.store_hits(packet_rays(rays, i), q.active, q.h, hits.subspan(size_t(i) * 8));
    }
  }

  void occluded_span(std::span<const Ray> rays, std::span<uint8_t> out) const noexcept {
    Work& w = work();
    const int count = load(rays, w, false);
    uint32_t done[kMaxPackets] = {};
    for (int i = 0; i < count; ++i) {
      Packet& q = w.packets[size_t(i)];
      const std::span<const Ray> r = packet_rays(rays, i);
      for (uint32_t b = q.active; b; b &= b - 1)
        if (t_.scene().occluded_by_planes(r[size_t(std::countr_zero(b))])) done[i] |= b & (~b + 1);
      q.live = q.active & ~done[i];
    }
    const InstanceQueries<Kernel>* in = t_.instances();
    if (in && in->tree().empty()) in = nullptr;
    if (!t_.bvh().empty() || in) {
      Groups g;
      group(w, g);
      if (!t_.bvh().empty()) {
        for (int o = 0; o < 8; ++o)
          if (g.size[o] > 0) any_group(rays, w, g.members[o], g.size[o], o, done);
        for (int k = 0; k < g.singles; ++k) {
          const int i = g.single[k];
          Packet& q = w.packets[size_t(i)];
          const std::span<const Ray> r = packet_rays(rays, i);
          if (q.live) done[i] |= t_.any_packet(0, q.live, q.p, setup(w, i, r), r, q.h.tfar);
        }
      }
      if (in) {  // then the rays still unoccluded, in the same groups, through the instances
        for (int i = 0; i < count; ++i) w.packets[size_t(i)].live = w.packets[size_t(i)].active & ~done[i];
        for (int o = 0; o < 8; ++o)
          if (g.size[o] > 0) any_instances(*in, rays, w, g.members[o], g.size[o], o, done);
        for (int k = 0; k < g.singles; ++k) {
          const int i = g.single[k];
          Packet& q = w.packets[size_t(i)];
          const std::span<const Ray> r = packet_rays(rays, i);
          if (q.live) done[i] |= in->any_packet(0, q.live, q.p, setup(w, i, r), r, q.h.tfar);
        }
      }
    }
    for (size_t i = 0; i < rays.size(); ++i) out[i] = uint8_t(done[i / 8] >> (i % 8) & 1u);
  }

  /// What the group shares: its beam, its direction signs (as flags and as +-1 for ordering
  /// children), the largest tfar of its rays, and each member's own beam (lane k % 8 of
  /// block k / 8 for member k).
  struct GroupBeam {
    PacketBeam beam;
    typename Kernel::Beam kbeam;  ///< what the kernel takes of `beam`
    float8 sx, sy, sz;
    float tfar_max;
    PacketBeams8 members[kMaxPackets / 8];
  };

  /// The beams of the group `members` of one octant and of each member, over their live rays.
  static void group_beam(const Work& w, const uint8_t* members, int n, int octant, GroupBeam& gb) {
    const bool neg[3] = {(octant & 1) != 0, (octant & 2) != 0, (octant & 4) != 0};
    constexpr float inf = std::numeric_limits<float>::infinity();
    const float8 inf8(inf);
    // Per member: rows omin[3], omax[3], imin[3], imax[3], tnear_min, tfar_max.
    alignas(32) float row[14][kMaxPackets];
    const int blocks = (n + 7) / 8;
    for (int k = 0; k < 8 * blocks; ++k) {
      const Packet* q = k < n ? &w.packets[members[k]] : nullptr;
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
  static uint64_t beam_hits(const GroupBeam& gb, const Vec3f& lo, const Vec3f& hi, int first, int last) {
    uint64_t maybe = 0;
    for (int blk = first / 8; blk <= last / 8; ++blk)
      maybe |= uint64_t(gb.members[blk].cull(gb.beam.neg, lo, hi)) << (8 * blk);
    const uint64_t upto_last = last >= 63 ? ~uint64_t(0) : (uint64_t(1) << (last + 1)) - 1;
    return maybe & upto_last & ~((uint64_t(1) << first) - 1);
  }

  /// A pushed subtree: the node or leaf, the range [first, last] of the group's members that
  /// may reach it, and its box (a leaf's box lives in its parent only).
  struct Entry {
    int32_t ref;
    uint8_t first, last;
    Vec3f lo, hi;
  };

  /// The traversal stack, left uninitialised: only pushed entries are read (zeroing kStackSize
  /// boxes per group was a measurable share of the instructions).
  struct Stack {
    union {
      Entry at[kStackSize];
    };
    Stack() {}
  };

  /// Narrows [first, last] to the first and the last member whose live lanes hit box [lo, hi]
  /// (an 8-ray slab test each, only for members whose beam may reach the box); first > last
  /// when none does.
  static void bound_range(const Work& w, const uint8_t* members, const GroupBeam& gb, const Vec3f& lo,
                          const Vec3f& hi, int& first, int& last) {
    uint64_t maybe = beam_hits(gb, lo, hi, first, last);
    auto hits = [&](int k) {
      const Packet& q = w.packets[members[k]];
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
  static void push_children(const Work& w, const uint8_t* members, const GroupBeam& gb, const Bvh8Node& n,
                            const Entry& e, Entry* stack, int& sp) {
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
      Entry& to = stack[sp++];
      const int c = kid[j];
      to.ref = n.child[c];
      to.first = kid_first[j];
      to.last = kid_last[j];
      to.lo = {n.lo_x[c], n.lo_y[c], n.lo_z[c]};
      to.hi = {n.hi_x[c], n.hi_y[c], n.hi_z[c]};
    }
  }

  /// The members of entry `e` (a leaf) whose live lanes hit its box, and those lanes.
  static int leaf_packets(const Work& w, const uint8_t* members, const GroupBeam& gb, const Entry& e, uint8_t* which,
                          uint32_t* lanes) {
    int m = 0;
    for (uint64_t maybe = beam_hits(gb, e.lo, e.hi, e.first, e.last); maybe; maybe &= maybe - 1) {
      const int k = std::countr_zero(maybe);
      const Packet& q = w.packets[members[k]];
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
  static int split_by_rays(uint8_t* which, uint32_t* lanes, int m, uint32_t count, F&& f) {
    int kept = 0;
    for (int j = 0; j < m; ++j) {
      if (Traversal<Kernel>::by_rays(lanes[j], count)) {
        f(which[j], lanes[j]);
      } else {
        which[kept] = which[j];
        lanes[kept++] = lanes[j];
      }
    }
    return kept;
  }

  /// The group `members` of one octant through the tree, taking hits for instance `inst`
  /// (kNoInstance: the world's tree).
  void closest_group(std::span<const Ray> rays, Work& w, const uint8_t* members, int n, int octant,
                     uint32_t inst) const noexcept {
    GroupBeam gb;
    group_beam(w, members, n, octant, gb);
    Stack st;
    Entry* stack = st.at;
    stack[0] = {0, 0, uint8_t(n - 1), t_.bvh().bounds.lo, t_.bvh().bounds.hi};
    int sp = 1;
    uint8_t which[kMaxPackets];
    uint32_t lanes[kMaxPackets];
    while (sp > 0) {
      const Entry& e = stack[--sp];              // read in place (push_children reads it before pushing)
      if (e.last - e.first < kPacketFallback) {  // few packets left: each continues on its own
        for (int k = e.first; k <= e.last; ++k) {
          Packet& q = w.packets[members[k]];
          const uint32_t m = intersect_box_octant(q.p, gb.beam.neg, e.lo, e.hi, q.h.tfar) & q.live;  // lanes here
          if (!m) continue;
          const std::span<const Ray> r = packet_rays(rays, members[k]);
          t_.closest_packet(e.ref, m, q.p, setup(w, members[k], r), r, q.h, inst);
        }
        continue;
      }
      if (!is_leaf(e.ref)) {
        push_children(w, members, gb, t_.bvh().nodes[size_t(e.ref)], e, stack, sp);
        continue;
      }
      int m = leaf_packets(w, members, gb, e, which, lanes);
      if (!m) continue;
      const Leaf leaf = t_.bvh().leaf(e.ref);
      if (const uint32_t id = t_.analytic_leaf(leaf); id != kInvalidId) {
        for (int j = 0; j < m; ++j)
          t_.analytic_packet(id, packet_rays(rays, which[j]), lanes[j], w.packets[which[j]].h);
        continue;
      }
      const typename Kernel::Block kb{LeafView(leaf)};  // the leaf read once
      const typename Kernel::Origins og(kb, gb.kbeam);  // the group's origins against the leaf
      m = split_by_rays(which, lanes, m, leaf.n, [&](int i, uint32_t here) {
        Packet& q = w.packets[size_t(i)];
        t_.leaf_by_rays(leaf, kb, og, here, q.p, packet_rays(rays, i), q.h, inst);
      });
      if (m == 0) continue;
      for (uint32_t k = 0; k < leaf.n; ++k) {
        const uint32_t id = leaf.prim(k);
        const typename Kernel::Triangle tri(kb, k, og);  // set up once for every packet
        for (int j = 0; j < m; ++j) {
          Packet& q = w.packets[which[j]];
          Traversal<Kernel>::update(q.h, q.kp.test(tri, q.h.tfar, lanes[j]), lanes[j], id, inst);
        }
      }
    }
  }

  void any_group(std::span<const Ray> rays, Work& w, const uint8_t* members, int n, int octant,
                 uint32_t* done) const noexcept {
    GroupBeam gb;
    group_beam(w, members, n, octant, gb);
    Stack st;
    Entry* stack = st.at;
    stack[0] = {0, 0, uint8_t(n - 1), t_.bvh().bounds.lo, t_.bvh().bounds.hi};
    int sp = 1;
    int live_packets = 0;
    for (int k = 0; k < n; ++k) live_packets += w.packets[members[k]].live != 0;
    auto occlude = [&](int i, uint32_t found) {  // packet index i
      Packet& q = w.packets[size_t(i)];
      done[i] |= found;
      const bool was_live = q.live != 0;
      q.live &= ~found;
      live_packets -= was_live && !q.live;
    };
    uint8_t which[kMaxPackets];
    uint32_t lanes[kMaxPackets];
    while (sp > 0 && live_packets > 0) {
      const Entry& e = stack[--sp];  // read in place (push_children reads it before pushing)
      if (e.last - e.first < kPacketFallback) {
        for (int k = e.first; k <= e.last; ++k) {
          Packet& q = w.packets[members[k]];
          const uint32_t m = q.live ? intersect_box_octant(q.p, gb.beam.neg, e.lo, e.hi, q.h.tfar) & q.live : 0u;
          if (!m) continue;
          const std::span<const Ray> r = packet_rays(rays, members[k]);
          occlude(members[k], t_.any_packet(e.ref, m, q.p, setup(w, members[k], r), r, q.h.tfar));
        }
        continue;
      }
      if (!is_leaf(e.ref)) {
        push_children(w, members, gb, t_.bvh().nodes[size_t(e.ref)], e, stack, sp);
        continue;
      }
      int m = leaf_packets(w, members, gb, e, which, lanes);
      if (!m) continue;
      const Leaf leaf = t_.bvh().leaf(e.ref);
      if (const uint32_t id = t_.analytic_leaf(leaf); id != kInvalidId) {
        for (int j = 0; j < m; ++j)
          if (const uint32_t found = t_.analytic_any(id, packet_rays(rays, which[j]), lanes[j]))
            occlude(which[j], found);
        continue;
      }
      const typename Kernel::Block kb{LeafView(leaf)};  // the leaf read once
      m = split_by_rays(which, lanes, m, leaf.n, [&](int i, uint32_t here) {
        const Packet& q = w.packets[size_t(i)];
        if (const uint32_t found = t_.leaf_any_by_rays(leaf, kb, here, q.p, packet_rays(rays, i), q.h.tfar))
          occlude(i, found);
      });
      for (uint32_t k = 0; k < leaf.n && m > 0; ++k) {
        const typename Kernel::Triangle tri(kb, k);  // set up once for every packet
        for (int j = 0; j < m; ++j) {
          Packet& q = w.packets[which[j]];
          const uint32_t found = simd::movemask(q.kp.test(tri, q.h.tfar, lanes[j]).hit) & lanes[j];
          if (!found) continue;
          occlude(which[j], found);
          lanes[j] &= ~found;
        }
        // Drop the packets whose lanes here are all occluded.
        int kept = 0;
        for (int j = 0; j < m; ++j)
          if (lanes[j]) {
            which[kept] = which[j];
            lanes[kept++] = lanes[j];
          }
        m = kept;
      }
    }
  }

  // ---- the instance level ----

  /// A pushed subtree of the instance tree: the members that reach it as bits (bit k: group
  /// member k), not a range as in the world's tree: over a field of many small instances the
  /// members between the first and the last that reach a box mostly miss it, and testing
  /// them cost more than the group saved (slower than 8-ray packets on a large field of
  /// instances; figures: docs/notes/2026-11-29-figures-from-code-comments.md).
  struct MaskEntry {
    int32_t ref;
    uint64_t reach;
    Vec3f lo, hi;
  };
  struct MaskStack {
    union {
      MaskEntry at[kStackSize];
    };
    MaskStack() {}
  };

  /// Whether the rays of the m members `which` (lanes `lanes`) reaching an instance whose box
  /// is centred at `at` are dense enough there for a group to pay in its mesh's tree: the
  /// distance between the first two rays of one packet (neighbours in a tile) where they pass
  /// `at` is at most kDenseGap times the typical leaf size of the mesh as placed. Measured on
  /// primary rays: where the gap is below a leaf size (a few instances filling the image)
  /// groups beat 8-ray packets; where it is many leaf sizes (a large field of small instances,
  /// a few packets reaching each) groups lose (figures:
  /// docs/notes/2026-11-29-figures-from-code-comments.md).
  static bool dense(const Work& w, const uint8_t* which, const uint32_t* lanes, int m, const Vec3f& at,
                    float leaf_size) {
    for (int j = 0; j < m; ++j) {
      if (std::popcount(lanes[j]) < 2) continue;
      const int a = std::countr_zero(lanes[j]), b = std::countr_zero(lanes[j] & (lanes[j] - 1));
      const Packet& q = w.packets[which[j]];
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

  /// The group `members` of one octant (world packets) down the instance tree; at each
  /// instance that kMinGroupPackets members or more reach, at_instance(instance id, the m
  /// members `which` reaching its box, their lanes there). A subtree that fewer members reach
  /// continues as their 8-ray packets through the instance level (InstanceQueries::
  /// closest_packet and any_packet, from that node): per_packet(node, packet index, lanes).
  /// `alive` says whether any member still needs tracing (any hit stops early).
  template <class AtInstance, class PerPacket, class Alive>
  void instance_groups(const InstanceQueries<Kernel>& in, const Work& w, const uint8_t* members, int n, int octant,
                       AtInstance&& at_instance, PerPacket&& per_packet, Alive&& alive) const noexcept {
    GroupBeam gb;
    group_beam(w, members, n, octant, gb);
    const InstanceTree& tree = in.tree();
    MaskStack st;
    MaskEntry* stack = st.at;
    stack[0] = {0, n == 64 ? ~uint64_t(0) : (uint64_t(1) << n) - 1, tree.bounds.lo, tree.bounds.hi};
    int sp = 1;
    const auto lanes_in = [&](int k, const Vec3f& lo, const Vec3f& hi) {  // member k's live lanes in a box
      const Packet& q = w.packets[members[k]];
      return q.live ? intersect_box_octant(q.p, gb.beam.neg, lo, hi, q.h.tfar) & q.live : 0u;
    };
    uint8_t which[kMaxPackets];
    uint32_t lanes[kMaxPackets];
    while (sp > 0 && alive()) {
      const MaskEntry e = stack[--sp];
      if (is_leaf(e.ref) || std::popcount(e.reach) < kMinGroupPackets) {
        int m = 0;
        for (uint64_t b = e.reach; b; b &= b - 1)
          if (const uint32_t here = lanes_in(std::countr_zero(b), e.lo, e.hi)) {
            which[m] = members[std::countr_zero(b)];
            lanes[m++] = here;
          }
        if (is_leaf(e.ref) && m >= kMinGroupPackets &&
            dense(w, which, lanes, m, (e.lo + e.hi) * 0.5f, in.placed(leaf_offset(e.ref)).leaf_size)) {
          at_instance(leaf_offset(e.ref), which, lanes, m);
        } else {
          for (int j = 0; j < m; ++j) per_packet(e.ref, which[j], lanes[j]);
        }
        continue;
      }
      // The children the group's beam may reach, each with the members whose rays hit its box
      // (a leaf's are tested when it is popped, with the hits found by then), nearest last.
      const Bvh8Node& node = tree.nodes[size_t(e.ref)];
      const uint32_t candidates = gb.beam.cull(node, gb.tfar_max);
      alignas(32) float key[8];
      near_first_keys(node, gb.sx, gb.sy, gb.sz).store_aligned(key);
      MaskEntry kids[8];
      float kid_key[8];
      int k = 0;
      const int first = std::countr_zero(e.reach), last = 63 - std::countl_zero(e.reach);
      for (uint32_t bits = candidates; bits; bits &= bits - 1) {
        const int c = std::countr_zero(bits);
        if (node.child[c] == kEmpty) continue;
        const Vec3f lo{node.lo_x[c], node.lo_y[c], node.lo_z[c]}, hi{node.hi_x[c], node.hi_y[c], node.hi_z[c]};
        uint64_t reach = beam_hits(gb, lo, hi, first, last) & e.reach;
        if (!is_leaf(node.child[c]))
          for (uint64_t b = reach; b; b &= b - 1)
            if (!lanes_in(std::countr_zero(b), lo, hi)) reach &= ~(b & (~b + 1));
        if (!reach) continue;
        int j = k++;
        for (; j > 0 && kid_key[j - 1] < key[c]; --j) {
          kids[j] = kids[j - 1];
          kid_key[j] = kid_key[j - 1];
        }
        kids[j] = {node.child[c], reach, lo, hi};
        kid_key[j] = key[c];
      }
      RP_DCHECK(sp + k <= kStackSize);
      for (int j = 0; j < k; ++j) stack[sp++] = kids[j];
    }
  }

  /// The lanes `lanes[j]` of the m world packets `which[j]` of `w` in the object space of
  /// instance `pl`, loaded as object packet j of `ow` (its rays in ow.rays, its hits left
  /// for the caller); the regrouping by object-space octant in `g`. Returns the object-space
  /// rays.
  static std::span<const Ray> to_object(const typename InstanceQueries<Kernel>::Placed& pl, std::span<const Ray> rays,
                                        const uint8_t* which, const uint32_t* lanes, int m, Work& ow, Groups& g) {
    for (int j = 0; j < m; ++j)
      object_rays(pl.world_to_object, packet_rays(rays, which[j]), lanes[j], &ow.rays[8 * size_t(j)]);
    const std::span<const Ray> orays(ow.rays.data(), 8 * size_t(m));
    LargePacketTraversal(*pl.mesh).load(orays, ow, false);
    group(ow, g);
    return orays;
  }

  /// Closest hits of the group `members` among the instances, into the world packets' hits.
  void closest_instances(const InstanceQueries<Kernel>& in, std::span<const Ray> rays, Work& w, const uint8_t* members,
                         int n, int octant) const noexcept {
    Work& ow = object_work();
    auto at_instance = [&](uint32_t id, const uint8_t* which, const uint32_t* lanes, int m) {
      const typename InstanceQueries<Kernel>::Placed& pl = in.placed(id);
      if (pl.mesh->bvh().empty()) return;
      Groups g;
      const std::span<const Ray> orays = to_object(pl, rays, which, lanes, m, ow, g);
      for (int j = 0; j < m; ++j) ow.packets[size_t(j)].h = w.packets[which[j]].h;  // t is the world t
      const LargePacketTraversal mesh(*pl.mesh);
      for (int o = 0; o < 8; ++o)
        if (g.size[o] > 0) mesh.closest_group(orays, ow, g.members[o], g.size[o], o, id);
      for (int k = 0; k < g.singles; ++k) {
        Packet& q = ow.packets[g.single[k]];
        const std::span<const Ray> r = packet_rays(orays, g.single[k]);
        pl.mesh->closest_packet(0, q.active, q.p, setup(ow, g.single[k], r), r, q.h, id);
      }
      for (int j = 0; j < m; ++j) w.packets[which[j]].h = ow.packets[size_t(j)].h;
    };
    auto per_packet = [&](int32_t ref, int i, uint32_t here) {
      Packet& q = w.packets[size_t(i)];
      const std::span<const Ray> r = packet_rays(rays, i);
      in.closest_packet(ref, here, q.p, setup(w, i, r), r, q.h);
    };
    instance_groups(in, w, members, n, octant, at_instance, per_packet, [] { return true; });
  }

  /// The lanes of the group `members` that some instance occludes, into `done` (and off the
  /// world packets' live lanes).
  void any_instances(const InstanceQueries<Kernel>& in, std::span<const Ray> rays, Work& w, const uint8_t* members,
                     int n, int octant, uint32_t* done) const noexcept {
    Work& ow = object_work();
    int live_packets = 0;
    for (int k = 0; k < n; ++k) live_packets += w.packets[members[k]].live != 0;
    auto occlude = [&](int i, uint32_t found) {  // world packet i
      if (!found) return;
      Packet& q = w.packets[size_t(i)];
      done[i] |= found;
      const bool was_live = q.live != 0;
      q.live &= ~found;
      live_packets -= was_live && !q.live;
    };
    auto at_instance = [&](uint32_t id, const uint8_t* which, const uint32_t* lanes, int m) {
      const typename InstanceQueries<Kernel>::Placed& pl = in.placed(id);
      if (pl.mesh->bvh().empty()) return;
      Groups g;
      const std::span<const Ray> orays = to_object(pl, rays, which, lanes, m, ow, g);
      uint32_t found[kMaxPackets] = {};
      const LargePacketTraversal mesh(*pl.mesh);
      for (int o = 0; o < 8; ++o)
        if (g.size[o] > 0) mesh.any_group(orays, ow, g.members[o], g.size[o], o, found);
      for (int k = 0; k < g.singles; ++k) {
        const int j = g.single[k];
        Packet& q = ow.packets[size_t(j)];
        const std::span<const Ray> r = packet_rays(orays, j);
        if (q.live) found[j] |= pl.mesh->any_packet(0, q.live, q.p, setup(ow, j, r), r, q.h.tfar);
      }
      for (int j = 0; j < m; ++j) occlude(which[j], found[j]);
    };
    auto per_packet = [&](int32_t ref, int i, uint32_t here) {
      const Packet& q = w.packets[size_t(i)];
      const std::span<const Ray> r = packet_rays(rays, i);
      occlude(i, in.any_packet(ref, here, q.p, setup(w, i, r), r, q.h.tfar));
    };
    instance_groups(in, w, members, n, octant, at_instance, per_packet, [&] { return live_packets > 0; });
  }

  const Traversal<Kernel>& t_;
};

}  // namespace rp::bvh8
