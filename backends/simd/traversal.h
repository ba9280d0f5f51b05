#pragma once
/// Single-ray and 8-ray packet traversal of the 8-wide BVH, templated on the triangle test
/// (Möller–Trumbore or watertight). Both start from any subtree, so the large-packet
/// traversal (large_packet.h) can hand them what it no longer traverses as a group: a packet
/// continues as an 8-ray packet, a packet with few live lanes as single rays. AVX2+FMA
/// translation units only.
///
/// The closest hit is the least (t, prim_id, instance_id): among primitives hit at exactly the
/// same t (a ray through a shared edge or vertex), the lowest prim_id, and among placements
/// of one primitive by several instances, the lowest instance id (kNoInstance, the largest,
/// for the world's own primitives). The rule does not depend on the order in which leaves or
/// instances are visited, so every traversal (single rays, 8-ray packets, large packets,
/// streams) gives every ray the same primitive, instance and t, u, v bits. (The unbounded
/// planes then take a hit at equal t, after any traversal: Scene::intersect_planes.)
///
/// A Traversal serves one tree: the world's (Bvh8 of build()), whose traversal also hands
/// each ray to the scene's instances (set_instances, instances.h) before the planes, or an
/// instanced mesh's (build_mesh), which the instances' traversal runs on object-space rays
/// with the instance's id (the `inst` arguments below: kNoInstance in the world's tree).

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <limits>
#include <span>

#include "backends/simd/bvh8.h"
#include "backends/simd/kernels.h"
#include "backends/simd/packet.h"
#include "engine/affine.h"
#include "engine/error.h"
#include "engine/scene.h"

namespace rp::bvh8 {

/// The queries the world's traversal makes of the instance level when the scene has instances
/// (implemented by InstanceTraversal, instances.h): a virtual call per ray or packet, and
/// only in scenes with instances.
template <class Kernel>
class Traversal;

template <class Kernel>
class InstanceQueries {
 public:
  /// One instance as the traversals read it: the map into its object space and the
  /// traversal of its mesh's tree.
  struct Placed {
    Affine3f world_to_object;
    const Traversal<Kernel>* mesh;
    /// The typical size of a leaf of the mesh's tree as placed, in world units (mean_leaf_size
    /// times the placement's mean scale): large packets use it to judge the rays' density.
    float leaf_size = 0.0f;
  };

  virtual ~InstanceQueries() = default;
  /// The tree over the instances' world boxes, whose leaf ~i is instance i.
  virtual const InstanceTree& tree() const noexcept = 0;
  /// Instance i of the scene.
  virtual const Placed& placed(uint32_t i) const noexcept = 0;
  /// Takes any closer hit of valid ray `r` among the instances into `best`.
  virtual void closest(const Ray& r, Hit& best) const noexcept = 0;
  /// True when some instance occludes valid ray `r`.
  virtual bool any(const Ray& r) const noexcept = 0;
  /// The same two from node `root` of the instance tree, for a ray set up already.
  virtual void closest(const Ray& r, const SingleRay& sr, int32_t root, Hit& best) const noexcept = 0;
  virtual bool any(const Ray& r, const SingleRay& sr, int32_t root) const noexcept = 0;
  /// Takes closer hits of the lanes `mask` of packet `p` (the rays `rays`, set up in `ps`) in
  /// the subtree `root` of the instance tree (0: all of it; a leaf: one instance) into `h`.
  virtual void closest_packet(int32_t root, uint32_t mask, const RayPacket& p, const PacketSetup<Kernel>& ps,
                              std::span<const Ray> rays, PacketHits& h) const noexcept = 0;
  /// The lanes of `live` that some instance of subtree `root` occludes (tfar per lane).
  virtual uint32_t any_packet(int32_t root, uint32_t live, const RayPacket& p, const PacketSetup<Kernel>& ps,
                              std::span<const Ray> rays, const float8& tfar) const noexcept = 0;
};

/// The lanes `mask` of `rays` (at most 8) in an instance's object space (rp::object_ray by
/// `world_to_object`: the single-ray path's bits) as `o[0..8)`; the other lanes an invalid ray.
inline void object_rays(const Affine3f& world_to_object, std::span<const Ray> rays, uint32_t mask, Ray* o) {
  constexpr Ray kInactive{{0.0f, 0.0f, 0.0f}, 1.0f, {1.0f, 1.0f, 1.0f}, 0.0f};  // tnear > tfar: invalid
  for (size_t lane = 0; lane < 8; ++lane)
    o[lane] = (mask >> lane & 1u) ? object_ray(rays[lane], world_to_object) : kInactive;
}

/// Traversal stack bound: the build keeps binary depth <= 64 + log2(n) < 100, so an 8-wide
/// tree holds at most 7 pending children per level.
inline constexpr int kStackSize = 1024;

/// A packet entry with at most this many active lanes continues as single rays.
inline constexpr int kSingleRayLanes = 2;

/// A subtree a single ray still has to visit, with its entry distance.
struct DistanceEntry {
  int32_t ref;
  float t;
};

/// Pushes the children `bits` of node `n` onto `stack` at `sp`, sorted there by descending
/// entry distance `dist` (a stable insertion sort: ties keep the higher slot nearer the top),
/// then pops the nearest and returns its reference: near-first order for a single ray.
RP_SIMD_INLINE int32_t push_near_first(const Bvh8Node& n, uint32_t bits, const float* dist, DistanceEntry* stack,
                                       int& sp) {
  RP_DCHECK(sp + 8 <= kStackSize);
  DistanceEntry* hit = stack + sp;
  int k = 0;
  for (; bits; bits &= bits - 1) {
    const int c = std::countr_zero(bits);
    const DistanceEntry e{n.child[c], dist[c]};
    int j = k++;
    for (; j > 0 && hit[j - 1].t < e.t; --j) hit[j] = hit[j - 1];
    hit[j] = e;
  }
  sp += k - 1;
  return hit[k - 1].ref;
}

/// Single-ray and 8-ray packet traversal of one tree (see the top of this file).
template <class Kernel>
class Traversal {
 public:
  Traversal(const Bvh8& bvh, const Scene& scene) : bvh_(bvh), scene_(scene) {}

  const Bvh8& bvh() const { return bvh_; }
  const Scene& scene() const { return scene_; }

  /// The world's traversal hands every ray to `instances` too (null: the scene has none).
  void set_instances(const InstanceQueries<Kernel>* instances) { instances_ = instances; }
  const InstanceQueries<Kernel>* instances() const { return instances_; }

  // ---- single rays: one ray against the 8 children of a node ----

  /// Closest hit of one ray (a miss for an invalid one), the instances and planes included.
  Hit intersect_single(const Ray& r) const noexcept {
    Hit best;
    if (!valid_ray(r)) return best;
    if (!bvh_.empty()) closest(r, 0, best);
    finish_single(r, best);
    return best;
  }

  /// What follows a valid ray's traversal of the world's tree: the instances, then the planes.
  void finish_single(const Ray& r, Hit& best) const noexcept {
    if (instances_) instances_->closest(r, best);
    scene_.intersect_planes(r, best);
  }

  /// Any hit of one valid ray, the instances and planes included; stops at the first.
  bool occluded_single(const Ray& r) const noexcept {
    if (scene_.occluded_by_planes(r)) return true;
    return (!bvh_.empty() && any(r, 0)) || (instances_ && instances_->any(r));
  }

  /// Closest hit of a valid ray in the subtree `root`, replacing `best` by any hit within
  /// [tnear, min(tfar, best.t)]; a hit taken names instance `inst`. Children are visited
  /// near-first by their entry distance, the far ones pushed first; popped entries farther
  /// than the current hit are skipped.
  void closest(const Ray& r, int32_t root, Hit& best, uint32_t inst = kNoInstance) const noexcept {
    closest(r, SingleRay(r), root, best, inst);
  }

  /// The same for a ray set up already (sr = SingleRay(r)).
  void closest(const Ray& r, const SingleRay& sr, int32_t root, Hit& best, uint32_t inst = kNoInstance) const noexcept {
    float tfar = std::min(r.tfar, best.t);
    const typename Kernel::Single kr(r);
    DistanceEntry stack[kStackSize];
    int sp = 0;
    int32_t ref = root;
    for (;;) {
      if (!is_leaf(ref)) {
        const Bvh8Node& n = bvh_.nodes[size_t(ref)];
        float8 t_enter;
        uint32_t bits = intersect_node(n, sr, r.tnear, tfar, t_enter);
        if (bits) {
          if ((bits & (bits - 1)) == 0) {
            ref = n.child[std::countr_zero(bits)];
            continue;
          }
          alignas(32) float dist[8];
          t_enter.store_aligned(dist);
          const uint32_t rest = bits & (bits - 1);
          if ((rest & (rest - 1)) == 0) {  // two children: one compare, push the far one
            const int a = std::countr_zero(bits), b = std::countr_zero(rest);
            const bool a_near = dist[a] < dist[b];  // ties: the higher slot first, as below
            const int near = a_near ? a : b, far = a_near ? b : a;
            prefetch_children(n, 1u << far);
            RP_DCHECK(sp < kStackSize);
            stack[sp++] = {n.child[far], dist[far]};
            ref = n.child[near];
            continue;
          }
          prefetch_children(n, bits);
          ref = push_near_first(n, bits, dist, stack, sp);
          continue;
        }
      } else {
        // The leaf's size is in its first byte, and the rows past it wait for that byte: ask
        // for the lines of a typical leaf at once (measured faster on diffuse rays; figures:
        // docs/notes/2026-11-29-figures-from-code-comments.md).
        prefetch_leaf(ref);
        const Leaf leaf = bvh_.leaf(ref);
        if (const uint32_t id = analytic_leaf(leaf); id != kInvalidId) {
          Ray rr = r;
          rr.tfar = tfar;
          const Intersection<float> ah = scene_.intersect_analytic(id, rr);
          if (ah.hit && (ah.t < tfar || before(id, kNoInstance, best))) {
            tfar = ah.t;
            best = {ah.t, id, ah.u, ah.v};
          }
        } else {
          leaf_single(leaf, typename Kernel::Block(LeafView(leaf)), kr, tfar, best, inst);
        }
      }
      for (;;) {  // pop, skipping subtrees entered beyond the current hit
        if (sp == 0) return;
        const DistanceEntry e = stack[--sp];
        if (e.t <= std::fma(tfar, kSlabPad, sr.pad)) {  // conservative, as intersect_node
          ref = e.ref;
          break;
        }
      }
    }
  }

  /// The triangles of `leaf` (read into `lv`) against one ray (set up in `kr`) whose closest
  /// hit so far is `best`, searching up to `tfar` (best.t, or the ray's tfar before any hit):
  /// takes a closer hit, or one at the same t with a lower (prim_id, instance) (the rule at
  /// the top of this file; `inst` places the leaf's triangles). True when it took one.
  RP_SIMD_INLINE static bool leaf_single(const Leaf& leaf, const typename Kernel::Block& kb,
                                         const typename Kernel::Single& kr, float& tfar, Hit& best,
                                         uint32_t inst = kNoInstance, const typename Kernel::Origins* og = nullptr) {
    const TriHit8 h = og ? kr.block(kb, float8(tfar), *og) : kr.block(kb, float8(tfar));
    const uint32_t bits = simd::movemask(h.hit) & ((1u << leaf.n) - 1);
    if (!bits) return false;
    const float tmin =
        simd::reduce_min(xsimd::select(simd::mask_from_bits(bits), h.t, float8(std::numeric_limits<float>::infinity())));
    const int lane = lowest_prim(leaf, simd::movemask(h.t == float8(tmin)) & bits);
    const uint32_t id = leaf.prim(uint32_t(lane));
    if (!(tmin < tfar || before(id, inst, best))) return false;
    tfar = tmin;
    best = {tmin, id, h.u.get(size_t(lane)), h.v.get(size_t(lane)), inst};
    return true;
  }

  /// Any hit of a valid ray in the subtree `root`.
  bool any(const Ray& r, int32_t root) const noexcept { return any(r, SingleRay(r), root); }

  /// The same for a ray set up already (sr = SingleRay(r)).
  bool any(const Ray& r, const SingleRay& sr, int32_t root) const noexcept {
    const typename Kernel::Single kr(r);
    const float8 tfar8(r.tfar);
    int32_t stack[kStackSize];
    stack[0] = root;
    int sp = 1;
    while (sp > 0) {
      const int32_t ref = stack[--sp];
      if (!is_leaf(ref)) {
        const Bvh8Node& n = bvh_.nodes[size_t(ref)];
        float8 t_enter;
        RP_DCHECK(sp + 8 <= kStackSize);
        for (uint32_t bits = intersect_node(n, sr, r.tnear, r.tfar, t_enter); bits; bits &= bits - 1)
          stack[sp++] = n.child[std::countr_zero(bits)];
        continue;
      }
      const Leaf leaf = bvh_.leaf(ref);
      if (const uint32_t id = analytic_leaf(leaf); id != kInvalidId) {
        if (scene_.intersect_analytic(id, r).hit) return true;
      } else if (simd::movemask(kr.block(typename Kernel::Block(LeafView(leaf)), tfar8).hit) & ((1u << leaf.n) - 1)) {
        return true;
      }
    }
    return false;
  }

  /// Starts loading the nodes (or leaf blocks) of the children in `bits`, which traversal is
  /// about to visit or push: hides part of the memory latency that dominates traversal.
  void prefetch_children(const Bvh8Node& n, uint32_t bits) const noexcept {
    for (; bits; bits &= bits - 1) {
      const int32_t c = n.child[std::countr_zero(bits)];
      if (is_leaf(c)) {
        prefetch_leaf(c);
      } else {
        const char* p = reinterpret_cast<const char*>(&bvh_.nodes[size_t(c)]);
        for (uint32_t off = 0; off < sizeof(Bvh8Node); off += 64) simd::prefetch(p + off);
      }
    }
  }

  /// Starts loading leaf `ref`: its size is in the leaf, so the bytes of a typical full leaf
  /// (8 triangles, 10 vertices), from anywhere in a line.
  void prefetch_leaf(int32_t ref) const noexcept {
    const char* p = reinterpret_cast<const char*>(bvh_.leaf_data.data() + leaf_offset(ref));
    constexpr uint32_t kBytes = 4 * leaf_words(8, 10);
    for (uint32_t off = 0; off < kBytes; off += 64) simd::prefetch(p + off);
    simd::prefetch(p + kBytes - 1);
  }

  // ---- packets: 8 rays against one node's boxes ----

  /// Closest hits of the lanes of `mask` of packet `p` (rays `rays`, set up in `ps`) in the
  /// subtree `root`, improving `h` (hits taken name instance `inst`). Below kSingleRayLanes
  /// live lanes an entry's rays continue one at a time.
  void closest_packet(int32_t root, uint32_t mask, const RayPacket& p, const PacketSetup<Kernel>& ps,
                      std::span<const Ray> rays, PacketHits& h, uint32_t inst = kNoInstance) const noexcept {
    PacketEntry stack[kStackSize];
    stack[0] = {root, mask};
    int sp = 1;
    while (sp > 0) {
      const PacketEntry e = stack[--sp];
      if (simd::lane_count(e.mask) <= kSingleRayLanes) {
        single_rays_closest(e.ref, e.mask, rays, h, inst);
        continue;
      }
      if (!is_leaf(e.ref)) {
        Child kids[8];
        const int k = ordered_children(bvh_.nodes[size_t(e.ref)], p, ps, h.tfar, e.mask, kids);
        RP_DCHECK(sp + k <= kStackSize);
        for (int j = 0; j < k; ++j) stack[sp++] = {kids[j].ref, kids[j].mask};
        continue;
      }
      leaf_closest(e.ref, e.mask, p, ps, rays, h, inst);
    }
  }

  /// The primitives of leaf `ref` against the lanes of `mask` (set up in `ps`), improving `h`:
  /// a lane at a time when few lanes reach the leaf (leaf_by_rays), else a triangle at a time.
  void leaf_closest(int32_t ref, uint32_t mask, const RayPacket& p, const PacketSetup<Kernel>& ps,
                    std::span<const Ray> rays, PacketHits& h, uint32_t inst = kNoInstance) const noexcept {
    const Leaf leaf = bvh_.leaf(ref);
    if (const uint32_t id = analytic_leaf(leaf); id != kInvalidId) {
      analytic_packet(id, rays, mask, h);
      return;
    }
    const typename Kernel::Block kb{LeafView(leaf)};
    const typename Kernel::Origins og(kb, ps.kbeam);
    if (by_rays(mask, leaf.n)) {
      leaf_by_rays(leaf, kb, og, mask, p, rays, h, inst);
      return;
    }
    for (uint32_t k = 0; k < leaf.n; ++k)
      update(h, ps.kp.test(typename Kernel::Triangle(kb, k, og), h.tfar, mask), mask, leaf.prim(k), inst);
  }

  /// True when testing a leaf of n triangles one lane of `mask` at a time (each lane against
  /// the n triangles in one 8-wide test) takes fewer kernel calls than one triangle at a
  /// time against the packet: at most n / 2 lanes.
  static bool by_rays(uint32_t mask, uint32_t n) { return 2u * uint32_t(std::popcount(mask)) <= n; }

  /// The triangles of `leaf` (read into `kb`, once for every lane and packet that takes it
  /// this way) against each lane of `mask` in turn, by the single-ray test: the same hits and
  /// bits as a triangle at a time.
  void leaf_by_rays(const Leaf& leaf, const typename Kernel::Block& kb, const typename Kernel::Origins& og,
                    uint32_t mask, const RayPacket& p, std::span<const Ray> rays, PacketHits& h,
                    uint32_t inst = kNoInstance) const noexcept {
    h.each_lane(mask, [&](int lane, Hit& hit) {
      float tfar = hit.t;
      leaf_single(leaf, kb, typename Kernel::Single(p, lane, rays[size_t(lane)]), tfar, hit, inst, &og);
    });
  }

  /// The lanes of `mask` that a triangle of `leaf` occludes, each lane against the leaf's
  /// triangles in one single-ray test, as leaf_by_rays does for closest hits.
  uint32_t leaf_any_by_rays(const Leaf& leaf, const typename Kernel::Block& kb, uint32_t mask, const RayPacket& p,
                            std::span<const Ray> rays, const float8& tfar) const noexcept {
    uint32_t found = 0;
    for (uint32_t b = mask; b; b &= b - 1) {
      const int lane = std::countr_zero(b);
      const TriHit8 m =
          typename Kernel::Single(p, lane, rays[size_t(lane)]).block(kb, simd::broadcast_lane(tfar, lane));
      if (simd::movemask(m.hit) & ((1u << leaf.n) - 1)) found |= b & (~b + 1);
    }
    return found;
  }

  /// Any hits of the lanes of `live` of packet `p` in the subtree `root` (tfar per lane);
  /// returns the lanes found occluded. Stops once every live lane is.
  uint32_t any_packet(int32_t root, uint32_t live, const RayPacket& p, const PacketSetup<Kernel>& ps,
                      std::span<const Ray> rays, const float8& tfar) const noexcept {
    PacketEntry stack[kStackSize];
    stack[0] = {root, live};
    int sp = 1;
    uint32_t done = 0;
    while (sp > 0 && live & ~done) {
      PacketEntry e = stack[--sp];
      e.mask &= ~done;
      if (!e.mask) continue;
      if (simd::lane_count(e.mask) <= kSingleRayLanes) {
        for (uint32_t b = e.mask; b; b &= b - 1)
          if (any(rays[size_t(std::countr_zero(b))], e.ref)) done |= b & (~b + 1);
        continue;
      }
      if (!is_leaf(e.ref)) {
        Child kids[8];
        const int k = ordered_children(bvh_.nodes[size_t(e.ref)], p, ps, tfar, e.mask, kids);
        RP_DCHECK(sp + k <= kStackSize);
        for (int j = 0; j < k; ++j) stack[sp++] = {kids[j].ref, kids[j].mask};
        continue;
      }
      done |= leaf_any(e.ref, e.mask, ps, rays, tfar);
    }
    return done;
  }

  /// The lanes of `mask` that some primitive of leaf `ref` occludes.
  uint32_t leaf_any(int32_t ref, uint32_t mask, const PacketSetup<Kernel>& ps, std::span<const Ray> rays,
                    const float8& tfar) const noexcept {
    const Leaf leaf = bvh_.leaf(ref);
    if (const uint32_t id = analytic_leaf(leaf); id != kInvalidId) return analytic_any(id, rays, mask);
    const typename Kernel::Block kb{LeafView(leaf)};
    uint32_t done = 0;
    for (uint32_t k = 0; k < leaf.n && mask; ++k) {
      const uint32_t hit = simd::movemask(ps.kp.test(typename Kernel::Triangle(kb, k), tfar, mask).hit) & mask;
      done |= hit;
      mask &= ~hit;
    }
    return done;
  }

  /// Closest hits of up to 8 rays as one packet, the instances and planes included.
  void intersect_packet(std::span<const Ray> rays, std::span<Hit> hits) const noexcept {
    RayPacket p;
    PacketHits h;
    const uint32_t active = load_packet(rays, p, h.tfar);
    h.clear();
    if (active && (!bvh_.empty() || instances_)) {
      const PacketSetup<Kernel> ps(p, rays, active);
      if (!bvh_.empty()) closest_packet(0, active, p, ps, rays, h);
      if (instances_) instances_->closest_packet(0, active, p, ps, rays, h);
    }
    store_hits(rays, active, h, hits);
  }

  /// Any hits of up to 8 rays as one packet, the planes included.
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
    if (live && (!bvh_.empty() || instances_)) {
      const PacketSetup<Kernel> ps(p, rays, live);
      if (!bvh_.empty()) done |= any_packet(0, live, p, ps, rays, tfar);
      if (instances_ && (live & ~done)) done |= instances_->any_packet(0, live & ~done, p, ps, rays, tfar);
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

  /// True when primitive `id` placed by instance `inst` comes before `best`'s in the
  /// closest-hit rule's order at equal t (the top of this file).
  static bool before(uint32_t id, uint32_t inst, const Hit& best) {
    return id < best.prim_id || (id == best.prim_id && inst < best.instance_id);
  }

  /// Takes the hits `m` of primitive `id` (placed by instance `inst`) for the lanes of
  /// `mask`: closer ones, and ones at the same t when (id, inst) comes first (the
  /// closest-hit rule at the top of this file).
  static void update(PacketHits& h, const TriHit8& m, uint32_t mask, uint32_t id, uint32_t inst = kNoInstance) {
    uint32_t bits = simd::movemask(m.hit) & mask;
    if (!bits) return;
    if (const uint32_t ties = simd::movemask(m.t == h.tfar) & bits)  // rare: exactly equal t
      for (uint32_t b = ties; b; b &= b - 1) {
        const int lane = std::countr_zero(b);
        if (!(id < h.prim[lane] || (id == h.prim[lane] && inst < h.inst[lane]))) bits &= ~(b & -b);
      }
    if (!bits) return;
    const mask8 upd = simd::mask_from_bits(bits);
    h.tfar = xsimd::select(upd, m.t, h.tfar);
    h.u = xsimd::select(upd, m.u, h.u);
    h.v = xsimd::select(upd, m.v, h.v);
    for (uint32_t b = bits; b; b &= b - 1) {
      h.prim[std::countr_zero(b)] = id;
      h.inst[std::countr_zero(b)] = inst;
    }
  }

  /// Of the slots `at` (non-empty) of `leaf`, the one with the lowest prim_id.
  static int lowest_prim(const Leaf& leaf, uint32_t at) {
    int best = std::countr_zero(at);
    for (uint32_t b = at & (at - 1); b; b &= b - 1)  // rare: several triangles at exactly one t
      if (leaf.prim(uint32_t(std::countr_zero(b))) < leaf.prim(uint32_t(best))) best = std::countr_zero(b);
    return best;
  }

  /// The prim_id of `leaf` when it is an analytic primitive, else kInvalidId. The build gives
  /// an analytic primitive a leaf of its own, so a leaf is all triangles (one 8-wide test) or
  /// one analytic primitive (its scalar routine).
  uint32_t analytic_leaf(const Leaf& leaf) const noexcept {
    if (leaf.n != 1 || !bvh_.has_analytic) return kInvalidId;
    const uint32_t id = leaf.prim(0);
    return id >= bvh_.first_analytic ? id : kInvalidId;
  }

  /// The lanes of `mask` whose rays analytic primitive `id` occludes, by its scalar routine.
  uint32_t analytic_any(uint32_t id, std::span<const Ray> rays, uint32_t mask) const noexcept {
    uint32_t found = 0;
    for (uint32_t b = mask; b; b &= b - 1)
      if (scene_.intersect_analytic(id, rays[size_t(std::countr_zero(b))]).hit) found |= b & -b;
    return found;
  }

  /// Analytic primitive `id` against the lanes of `mask`, by its scalar routine.
  void analytic_packet(uint32_t id, std::span<const Ray> rays, uint32_t mask, PacketHits& h) const noexcept {
    h.each_lane(mask, [&](int lane, Hit& hit) {
      Ray r = rays[size_t(lane)];
      r.tfar = hit.t;
      const Intersection<float> a = scene_.intersect_analytic(id, r);
      if (a.hit && (a.t < hit.t || before(id, kNoInstance, hit))) hit = {a.t, id, a.u, a.v};
    });
  }


  /// A subtree an 8-ray packet still has to visit, with the lanes that reach it.
  struct PacketEntry {
    int32_t ref;
    uint32_t mask;
  };

  /// Children of `n` hit by any lane of `mask`, ordered near-first along the packet's
  /// direction signs (near_first_keys): the nearest ends up last.
  struct Child {
    int32_t ref;
    uint32_t mask;
    float key;
  };
  static int ordered_children(const Bvh8Node& n, const RayPacket& p, const PacketSetup<Kernel>& ps, const float8& tfar,
                              uint32_t mask, Child* out) {
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
      Child e{n.child[c], m, key[c]};
      int j = k++;
      for (; j > 0 && out[j - 1].key < e.key; --j) out[j] = out[j - 1];  // descending: nearest last
      out[j] = e;
    }
    return k;
  }

 private:
  /// The lanes of `mask` through the subtree `ref` one ray at a time: a packet whose rays
  /// have drifted apart costs 8 lanes of work per box and triangle for one or two useful
  /// ones, so below kSingleRayLanes active lanes the packet hands its rays to the single-ray
  /// traversal (Benthin et al., "Combining Single and Packet-Ray Tracing for Arbitrary Ray
  /// Distributions on the Intel MIC Architecture", IEEE TVCG 18(9), 2012).
  void single_rays_closest(int32_t ref, uint32_t mask, std::span<const Ray> rays, PacketHits& h,
                           uint32_t inst) const noexcept {
    h.each_lane(mask, [&](int lane, Hit& hit) { closest(rays[size_t(lane)], ref, hit, inst); });
  }

  const Bvh8& bvh_;
  const Scene& scene_;
  const InstanceQueries<Kernel>* instances_ = nullptr;
};

}  // namespace rp::bvh8
