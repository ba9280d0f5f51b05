#pragma once
/// The large-packet shape of the simd backend, for coherent spans (a renderer's tile, a bench's
/// primary or shadow rays): up to kMaxPackets 8-ray packets that share a direction octant
/// traverse a tree as one group, so a node is fetched and culled once for the whole group
/// instead of once per packet, and a leaf's triangles are set up once for every packet that
/// reaches it. One loop (trace_group) for every level (levels.h) and query (the group
/// policies below, over queries.h). AVX2+FMA translation units only.
///
/// Per inner node (Wald, Boulos and Shirley, "Ray Tracing Deformable Scenes using Dynamic
/// Bounding Volume Hierarchies", ACM TOG 26(1), 2007; Boulos, Wald and Shirley, "Geometric
/// and Arithmetic Culling Methods for Entire Ray Packets", 2006):
/// 1. the group's interval-arithmetic beam (the bounds of all its rays' origins and inverse
///    directions) culls the 8 children in one 8-wide step;
/// 2. for each surviving child, the members whose rays hit the child's box (an 8-ray slab
///    test each) go with it, or it is culled when there are none;
/// 3. children are pushed near-first along the group's direction signs.
/// The members of an entry are kept per level (GroupEntry): in a mesh's tree as a range, the
/// first and the last member that hit the box (partition traversal: Overbeck, Ramamoorthi and
/// Mark, "Large Ray Packets for Real-time Whitted Ray Tracing", IEEE RT 2008); in the instance
/// tree as bits (MaskEntry, below). At a mesh's leaf each member is tested against the leaf's
/// box; then each triangle is set up once (broadcast, and for Möller–Trumbore its normal) and
/// tested against every packet that reached the leaf. An entry with too few members continues
/// as their 8-ray packets (packet8.h) from that node, which in turn hand entries with few live
/// lanes to single rays; packets whose rays do not share an octant, or have a zero direction
/// component, and octants with fewer than kMinGroupPackets packets, are traced as 8-ray
/// packets from the root.
///
/// At an instance, the members whose rays reach its box are mapped into its object space
/// (rp::object_ray per lane, the single-ray path's bits), regrouped by their object-space
/// octants and traced through the mesh's tree as a large packet of their own by the same loop
/// and query, sharing the world packets' answers (the map keeps t the world t). So a group
/// fetches each instance's nodes and sets up each of its triangles once, as in a flat scene,
/// instead of once per 8-ray packet, where the rays are dense enough there for that to pay
/// (dense()). Hits are resolved by the rule of levels.h, so every answer is that of the other
/// shapes, bit for bit.

#include <algorithm>
#include <array>
#include <bit>
#include <limits>
#include <span>
#include <type_traits>

#include "backends/simd/group.h"
#include "backends/simd/traversal.h"

namespace rp::bvh8 {

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
  using Packet = GroupPacket<Kernel>;
  using Work = GroupWork<Kernel>;
  using GroupBeam = bvh8::GroupBeam<Kernel>;

  static Work& work() {
    static thread_local Work w;
    return w;
  }
  /// The scratch of the members of a group at one instance, in its object space.
  static Work& object_work() {
    static thread_local Work w;
    return w;
  }

  void intersect_span(std::span<const Ray> rays, std::span<Hit> hits) const noexcept {
    Work& w = work();
    const int count = load(rays, w, true);
    const InstanceLevel<Kernel>* in = t_.instances();
    if (!t_.world().empty() || in) {
      Groups g;
      group_octants(w, g);
      ClosestGroup q{w, rays};
      if (!t_.world().empty()) trace_groups(t_.world(), rays, w, g, q);
      if (in) trace_groups(*in, rays, w, g, q);  // then the same groups through the instances
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
    const InstanceLevel<Kernel>* in = t_.instances();
    if (!t_.world().empty() || in) {
      Groups g;
      group_octants(w, g);
      AnyGroup q{w, rays, done};
      if (!t_.world().empty()) trace_groups(t_.world(), rays, w, g, q);
      if (in) trace_groups(*in, rays, w, g, q);  // then the rays still unoccluded, in the same groups
    }
    for (size_t i = 0; i < rays.size(); ++i) out[i] = uint8_t(done[i / 8] >> (i % 8) & 1u);
  }

  /// The groups `g` of `w` through level `lv`: each octant's group by trace_group, the other
  /// packets as 8-ray packets from the root.
  template <class Level, class Q>
  void trace_groups(const Level& lv, std::span<const Ray> rays, Work& w, const Groups& g, Q& q) const noexcept {
    for (int o = 0; o < 8; ++o)
      if (g.size[o] > 0) trace_group(lv, rays, w, g.members[o], g.size[o], o, q);
    for (int k = 0; k < g.singles; ++k)
      if (const uint32_t lanes = w.packets[g.single[k]].live) q.per_packet(lv, 0, g.single[k], lanes);
  }

  /// The root entry of level `lv` for a group of n members.
  static RangeEntry root_entry(const MeshLevel<Kernel>& lv, int n) {
    return {0, 0, uint8_t(n - 1), lv.bounds().lo, lv.bounds().hi};
  }
  static MaskEntry root_entry(const InstanceLevel<Kernel>& lv, int n) {
    return {0, n == 64 ? ~uint64_t(0) : (uint64_t(1) << n) - 1, lv.bounds().lo, lv.bounds().hi};
  }

  /// Whether an entry's members are too few for a group: they continue as 8-ray packets.
  static bool few(const RangeEntry& e) { return e.last - e.first < kPacketFallback; }
  static bool few(const MaskEntry& e) { return std::popcount(e.reach) < kMinGroupPackets; }

  /// f(k) for each member k of an entry.
  template <class F>
  static void each_member(const RangeEntry& e, F&& f) {
    for (int k = e.first; k <= e.last; ++k) f(k);
  }
  template <class F>
  static void each_member(const MaskEntry& e, F&& f) {
    for (uint64_t b = e.reach; b; b &= b - 1) f(std::countr_zero(b));
  }

  /// The live lanes of packet `q` (of the octant `gb`) that hit box [lo, hi].
  RP_SIMD_INLINE static uint32_t lanes_in(const Packet& q, const GroupBeam& gb, const Vec3f& lo, const Vec3f& hi) {
    return q.live ? intersect_box_octant(q.p, gb.beam.neg, lo, hi, q.h.tfar) & q.live : 0u;
  }

  /// The group `members` (n packets of `w`, octant `octant`) through level `lv`, answering
  /// query `q`: the one loop of the large-packet shape.
  template <class Level, class Q>
  void trace_group(const Level& lv, std::span<const Ray> rays, Work& w, const uint8_t* members, int n, int octant,
                   Q& q) const noexcept {
    GroupBeam gb;
    group_beam(w, members, n, octant, gb);
    q.start(members, n);
    using Entry = GroupEntry<Level>;
    GroupStack<Entry> st;
    Entry* stack = st.at;
    stack[0] = root_entry(lv, n);
    int sp = 1;
    while (sp > 0 && q.alive()) {
      const Entry& e = stack[--sp];  // read in place (push_children reads it before pushing)
      if (few(e)) {                  // few packets left: each continues on its own
        each_member(e, [&](int k) {
          if (const uint32_t here = lanes_in(w.packets[members[k]], gb, e.lo, e.hi))
            q.per_packet(lv, e.ref, members[k], here);
        });
        continue;
      }
      if (!is_leaf(e.ref)) {
        push_children(lv, w, members, gb, lv.node(e.ref), e, stack, sp);
        continue;
      }
      group_leaf(lv, rays, w, members, gb, e, q);
    }
  }

  static void push_children(const MeshLevel<Kernel>&, const Work& w, const uint8_t* members, const GroupBeam& gb,
                            const Bvh8Node& n, const RangeEntry& e, RangeEntry* stack, int& sp) {
    bvh8::push_children(w, members, gb, n, e, stack, sp);
  }

  /// The children of instance-tree node `node` the group's beam may reach, each with the
  /// members whose rays hit its box (a leaf's are tested when it is popped, with the hits
  /// found by then), nearest last.
  static void push_children(const InstanceLevel<Kernel>&, const Work& w, const uint8_t* members, const GroupBeam& gb,
                            const Bvh8Node& node, const MaskEntry& e, MaskEntry* stack, int& sp) {
    const uint64_t e_reach = e.reach;
    const uint32_t candidates = gb.beam.cull(node, gb.tfar_max);
    alignas(32) float key[8];
    near_first_keys(node, gb.sx, gb.sy, gb.sz).store_aligned(key);
    MaskEntry kids[8];
    float kid_key[8];
    int k = 0;
    const int first = std::countr_zero(e_reach), last = 63 - std::countl_zero(e_reach);
    for (uint32_t bits = candidates; bits; bits &= bits - 1) {
      const int c = std::countr_zero(bits);
      if (node.child[c] == kEmpty) continue;
      const Vec3f lo{node.lo_x[c], node.lo_y[c], node.lo_z[c]}, hi{node.hi_x[c], node.hi_y[c], node.hi_z[c]};
      uint64_t reach = beam_hits(gb, lo, hi, first, last) & e_reach;
      if (!is_leaf(node.child[c]))
        for (uint64_t b = reach; b; b &= b - 1)
          if (!lanes_in(w.packets[members[std::countr_zero(b)]], gb, lo, hi)) reach &= ~(b & (~b + 1));
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

  /// A leaf of a mesh's tree: the members whose rays reach it, its primitives set up once
  /// for all of them.
  template <class Q>
  RP_SIMD_INLINE void group_leaf(const MeshLevel<Kernel>& lv, std::span<const Ray>, Work& w, const uint8_t* members,
                                 const GroupBeam& gb, const RangeEntry& e, Q& q) const noexcept {
    uint8_t which[kMaxPackets];
    uint32_t lanes[kMaxPackets];
    const int m = leaf_packets(w, members, gb, e, which, lanes);
    if (!m) return;
    const Leaf leaf = lv.bvh.leaf(e.ref);
    if (const uint32_t id = lv.analytic_leaf(leaf); id != kInvalidId) {
      for (int j = 0; j < m; ++j) q.analytic(lv.scene, id, which[j], lanes[j]);
      return;
    }
    q.triangles(leaf, gb.kbeam, which, lanes, m, lv.inst);
  }

  /// An instance (its box `e`): where kMinGroupPackets members or more reach it and their rays
  /// are dense there, they go through its mesh as a group of their own (at_instance); else as
  /// 8-ray packets through the instance level from here.
  template <class Q>
  void group_leaf(const InstanceLevel<Kernel>& lv, std::span<const Ray> rays, Work& w, const uint8_t* members,
                  const GroupBeam& gb, const MaskEntry& e, Q& q) const noexcept {
    uint8_t which[kMaxPackets];
    uint32_t lanes[kMaxPackets];
    int m = 0;
    for (uint64_t b = e.reach; b; b &= b - 1)
      if (const uint32_t here = lanes_in(w.packets[members[std::countr_zero(b)]], gb, e.lo, e.hi)) {
        which[m] = members[std::countr_zero(b)];
        lanes[m++] = here;
      }
    const uint32_t id = leaf_offset(e.ref);
    if (m >= kMinGroupPackets && dense(w, which, lanes, m, (e.lo + e.hi) * 0.5f, lv.placed[id].leaf_size)) {
      at_instance(lv, id, rays, which, lanes, m, q);
    } else {
      for (int j = 0; j < m; ++j) q.per_packet(lv, e.ref, which[j], lanes[j]);
    }
  }

  /// The lanes `lanes[j]` of the m world packets `which[j]` through the mesh of instance `id`
  /// as a large packet of their own, in its object space, by query `q`.
  template <class Q>
  void at_instance(const InstanceLevel<Kernel>& lv, uint32_t id, std::span<const Ray> rays, const uint8_t* which,
                   const uint32_t* lanes, int m, Q& q) const noexcept {
    const Placed& pl = lv.placed[id];
    if (pl.mesh->empty()) return;
    Work& ow = object_work();
    for (int j = 0; j < m; ++j)
      object_rays(pl.world_to_object, packet_rays(rays, which[j]), lanes[j], &ow.rays[8 * size_t(j)]);
    const std::span<const Ray> orays(ow.rays.data(), 8 * size_t(m));
    load(orays, ow, false);
    Groups g;
    group_octants(ow, g);
    auto oq = q.object(ow, orays, which, m);
    trace_groups(lv.mesh(id), orays, ow, g, oq);
    q.join(oq, which, m);
  }

  // ---- the queries ----

  struct AnyObjectGroup;

  /// Closest hits, into the packets' PacketHits.
  struct ClosestGroup {
    Work& w;
    std::span<const Ray> rays;
    static void start(const uint8_t*, int) {}
    static constexpr bool alive() { return true; }
    /// Packet i's lanes `lanes` through level `lv` from node `ref`, as an 8-ray packet.
    template <class Level>
    void per_packet(const Level& lv, int32_t ref, int i, uint32_t lanes) {
      Packet& q = w.packets[size_t(i)];
      const std::span<const Ray> r = packet_rays(rays, i);
      ClosestPacket<Kernel> pq{q.h};
      trace_packet(lv, ref, lanes, q.p, setup(w, i, r), r, pq);
    }
    void analytic(const Scene& scene, uint32_t id, int i, uint32_t lanes) {
      closest_analytic(scene, id, packet_rays(rays, i), lanes, w.packets[size_t(i)].h);
    }
    /// The triangles of `leaf` against the m packets `which` (lanes `lanes` there).
    RP_SIMD_INLINE void triangles(const Leaf& leaf, const typename Kernel::Beam& kbeam, uint8_t* which, uint32_t* lanes,
                                  int m, uint32_t inst) {
      const typename Kernel::Block kb{LeafView(leaf)};  // the leaf read once
      const typename Kernel::Origins og(kb, kbeam);     // the group's origins against the leaf
      m = split_by_rays(which, lanes, m, leaf.n, [&](int i, uint32_t here) {
        Packet& q = w.packets[size_t(i)];
        closest_by_rays<Kernel>(leaf, kb, og, here, q.p, packet_rays(rays, i), q.h, inst);
      });
      for (uint32_t k = 0; k < leaf.n && m > 0; ++k) {
        const uint32_t id = leaf.prim(k);
        const typename Kernel::Triangle tri(kb, k, og);  // set up once for every packet
        for (int j = 0; j < m; ++j) {
          Packet& q = w.packets[which[j]];
          take_closest(q.h, q.kp.test(tri, q.h.tfar, lanes[j]), lanes[j], id, inst);
        }
      }
    }
    /// The query of the m world packets `which` in an instance's object space (packets of
    /// `ow`): their hits so far, as t is the world t.
    ClosestGroup object(Work& ow, std::span<const Ray> orays, const uint8_t* which, int m) const {
      for (int j = 0; j < m; ++j) ow.packets[size_t(j)].h = w.packets[which[j]].h;
      return {ow, orays};
    }
    void join(const ClosestGroup& o, const uint8_t* which, int m) {
      for (int j = 0; j < m; ++j) w.packets[which[j]].h = o.w.packets[size_t(j)].h;
    }
  };

  /// Any hits: the lanes found occluded into done[packet], and off the packets' live lanes;
  /// a group stops once none of its members has a live lane.
  struct AnyGroup {
    Work& w;
    std::span<const Ray> rays;
    uint32_t* done;
    int live_packets = 0;
    void start(const uint8_t* members, int n) {
      live_packets = 0;
      for (int k = 0; k < n; ++k) live_packets += w.packets[members[k]].live != 0;
    }
    bool alive() const { return live_packets > 0; }
    RP_SIMD_INLINE void occlude(int i, uint32_t found) {
      if (!found) return;
      Packet& q = w.packets[size_t(i)];
      done[i] |= found;
      const bool was_live = q.live != 0;
      q.live &= ~found;
      live_packets -= was_live && !q.live;
    }
    template <class Level>
    void per_packet(const Level& lv, int32_t ref, int i, uint32_t lanes) {
      const Packet& q = w.packets[size_t(i)];
      const std::span<const Ray> r = packet_rays(rays, i);
      AnyPacket<Kernel> pq(q.h.tfar, lanes);
      trace_packet(lv, ref, lanes, q.p, setup(w, i, r), r, pq);
      occlude(i, pq.done);
    }
    void analytic(const Scene& scene, uint32_t id, int i, uint32_t lanes) {
      occlude(i, any_analytic(scene, id, packet_rays(rays, i), lanes));
    }
    RP_SIMD_INLINE void triangles(const Leaf& leaf, const typename Kernel::Beam&, uint8_t* which, uint32_t* lanes,
                                  int m, uint32_t /*inst*/) {
      const typename Kernel::Block kb{LeafView(leaf)};  // the leaf read once
      m = split_by_rays(which, lanes, m, leaf.n, [&](int i, uint32_t here) {
        const Packet& q = w.packets[size_t(i)];
        occlude(i, any_by_rays<Kernel>(leaf, kb, here, q.p, packet_rays(rays, i), q.h.tfar));
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
    /// The query of the m world packets `which` in an instance's object space (packets of
    /// `ow`), the lanes it finds occluded kept apart.
    AnyObjectGroup object(Work& ow, std::span<const Ray> orays, const uint8_t*, int) const {
      return AnyObjectGroup(ow, orays);
    }
    void join(const AnyGroup& o, const uint8_t* which, int m) {
      for (int j = 0; j < m; ++j) occlude(which[j], o.done[j]);
    }
  };

  /// AnyGroup over an instance's object-space packets, with the lanes found occluded.
  struct AnyObjectGroup : AnyGroup {
    uint32_t found[kMaxPackets] = {};
    AnyObjectGroup(Work& ow, std::span<const Ray> orays) : AnyGroup{ow, orays, found} {}
    AnyObjectGroup(const AnyObjectGroup&) = delete;
  };

  const Traversal<Kernel>& t_;
};

}  // namespace rp::bvh8
