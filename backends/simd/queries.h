#pragma once
/// The queries of the simd backend's traversal loops, as policies: what a query keeps per ray
/// (single_ray.h) or per 8-ray packet (packet8.h), how far its rays still search (tfar), when
/// it may stop, and what it does with a leaf's primitives. The loops and the levels
/// (levels.h) never test a primitive themselves, so a new query (a closest point, every hit
/// along a ray, a count, a mask, a filter) is a new policy here and in the large-packet and
/// stream shapes, not a new loop. AVX2+FMA translation units only.
///
/// - Closest: the closest hit by the rule of levels.h; children are visited near-first and
///   subtrees entered beyond the current hit are skipped.
/// - Any: whether anything is hit within [tnear, tfar]; stops at the first hit.
/// - GatedClosest, GatedAny, Every: single rays whose candidate hits pass a gate first (the
///   ray's mask against the geometry's, and the caller's filter: core/queries.h), and every
///   hit along a ray (all_hits, count_hits).
///
/// A policy runs unchanged at both levels: at an instance the loops run the same policy on the
/// object-space rays (its t is the world t), so the hits of every level meet in one state.

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "backends/simd/levels.h"
#include "backends/simd/moller_trumbore.h"

namespace rp::bvh8 {

/// Of the slots `at` (non-empty) of `leaf`, the one with the lowest prim_id.
inline int lowest_prim(const Leaf& leaf, uint32_t at) {
  int best = std::countr_zero(at);
  for (uint32_t b = at & (at - 1); b; b &= b - 1)  // rare: several triangles at exactly one t
    if (leaf.prim(uint32_t(std::countr_zero(b))) < leaf.prim(uint32_t(best))) best = std::countr_zero(b);
  return best;
}

/// The triangles of `leaf` (read into `kb`) against one ray (set up in `kr`) whose closest hit
/// so far is `best`, searching up to `tfar` (best.t, or the ray's tfar before any hit): takes
/// a closer hit, or one at the same t with a lower (prim_id, instance) (levels.h; `inst`
/// places the leaf's triangles). True when it took one.
template <class Kernel>
RP_SIMD_INLINE bool closest_in_block(const Leaf& leaf, const typename Kernel::Block& kb,
                                     const typename Kernel::Single& kr, float& tfar, Hit& best, uint32_t inst,
                                     const typename Kernel::Origins* og = nullptr) {
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

/// Takes the hits `m` of primitive `id` (placed by instance `inst`) for the lanes of `mask`:
/// closer ones, and ones at the same t when (id, inst) comes first (levels.h).
inline void take_closest(PacketHits& h, const TriHit8& m, uint32_t mask, uint32_t id, uint32_t inst) {
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

/// True when testing a leaf of n triangles one lane of `mask` at a time (each lane against
/// the n triangles in one 8-wide test) takes fewer kernel calls than one triangle at a time
/// against the packet: at most n / 2 lanes.
inline bool by_rays(uint32_t mask, uint32_t n) { return 2u * uint32_t(std::popcount(mask)) <= n; }

/// The triangles of `leaf` (read into `kb`, once for every lane and packet that takes it this
/// way) against each lane of `mask` in turn, by the single-ray test: the same hits and bits as
/// a triangle at a time.
template <class Kernel>
void closest_by_rays(const Leaf& leaf, const typename Kernel::Block& kb, const typename Kernel::Origins& og,
                     uint32_t mask, const RayPacket& p, std::span<const Ray> rays, PacketHits& h, uint32_t inst) {
  h.each_lane(mask, [&](int lane, Hit& hit) {
    float tfar = hit.t;
    closest_in_block<Kernel>(leaf, kb, typename Kernel::Single(p, lane, rays[size_t(lane)]), tfar, hit, inst, &og);
  });
}

/// The lanes of `mask` that a triangle of `leaf` occludes, each lane against the leaf's
/// triangles in one single-ray test, as closest_by_rays does for closest hits.
template <class Kernel>
uint32_t any_by_rays(const Leaf& leaf, const typename Kernel::Block& kb, uint32_t mask, const RayPacket& p,
                     std::span<const Ray> rays, const float8& tfar) {
  uint32_t found = 0;
  for (uint32_t b = mask; b; b &= b - 1) {
    const int lane = std::countr_zero(b);
    const TriHit8 m = typename Kernel::Single(p, lane, rays[size_t(lane)]).block(kb, simd::broadcast_lane(tfar, lane));
    if (simd::movemask(m.hit) & ((1u << leaf.n) - 1)) found |= b & (~b + 1);
  }
  return found;
}

/// Analytic primitive `id` against the lanes of `mask`, by its scalar routine.
inline void closest_analytic(const Scene& scene, uint32_t id, std::span<const Ray> rays, uint32_t mask, PacketHits& h) {
  h.each_lane(mask, [&](int lane, Hit& hit) {
    Ray r = rays[size_t(lane)];
    r.tfar = hit.t;
    const Intersection<float> a = scene.intersect_analytic(id, r);
    if (a.hit && (a.t < hit.t || before(id, kNoInstance, hit))) hit = {a.t, id, a.u, a.v};
  });
}

/// The lanes of `mask` whose rays analytic primitive `id` occludes, by its scalar routine.
inline uint32_t any_analytic(const Scene& scene, uint32_t id, std::span<const Ray> rays, uint32_t mask) {
  uint32_t found = 0;
  for (uint32_t b = mask; b; b &= b - 1)
    if (scene.intersect_analytic(id, rays[size_t(std::countr_zero(b))]).hit) found |= b & -b;
  return found;
}

// ---- closest hit ----

/// The closest hit of one ray: `best`, and tfar = min(the ray's tfar, best.t).
template <class Kernel>
struct ClosestSingle {
  static constexpr bool kNearFirst = true;  ///< children near-first; pops beyond tfar skipped
  Hit& best;
  float tfar;
  ClosestSingle(const Ray& r, Hit& b) : best(b), tfar(std::min(r.tfar, b.t)) {}
  static constexpr bool done() { return false; }
  /// Analytic primitive `id` against ray `r`; true when the query is answered.
  bool analytic(const Scene& scene, uint32_t id, const Ray& r) {
    Ray rr = r;
    rr.tfar = tfar;
    const Intersection<float> ah = scene.intersect_analytic(id, rr);
    if (ah.hit && (ah.t < tfar || before(id, kNoInstance, best))) {
      tfar = ah.t;
      best = {ah.t, id, ah.u, ah.v};
    }
    return false;
  }
  /// The triangles of a leaf (read into `kb`) against the ray (set up in `kr`), placed by `inst`.
  RP_SIMD_INLINE bool triangles(const Leaf& leaf, const typename Kernel::Block& kb, const typename Kernel::Single& kr,
                                uint32_t inst) {
    closest_in_block<Kernel>(leaf, kb, kr, tfar, best, inst);
    return false;
  }
};

/// The closest hits of the lanes of an 8-ray packet, `h` (its tfar: each lane's search limit).
template <class Kernel>
struct ClosestPacket {
  using Single = ClosestSingle<Kernel>;
  PacketHits& h;
  static constexpr bool live() { return true; }
  static uint32_t pending(uint32_t mask) { return mask; }
  const float8& tfar() const { return h.tfar; }
  /// f(ray, single-ray query) for each lane of `mask`, on that lane's hit.
  template <class F>
  void each_single(uint32_t mask, std::span<const Ray> rays, F&& f) {
    h.each_lane(mask, [&](int lane, Hit& hit) {
      const Ray& r = rays[size_t(lane)];
      Single s(r, hit);
      f(r, s);
    });
  }
  /// The query of the lanes `valid` in an instance's object space (`tfar` theirs there): the
  /// same hits, as the map keeps t the world t.
  ClosestPacket& object(uint32_t /*valid*/, const float8& /*tfar*/) { return *this; }
  void join(const ClosestPacket&) {}
  void analytic(const Scene& scene, uint32_t id, std::span<const Ray> rays, uint32_t mask) {
    closest_analytic(scene, id, rays, mask, h);
  }
  /// The triangles of `leaf` against the lanes of `mask` (set up in `ps`): a lane at a time
  /// when few lanes reach the leaf (by_rays), else a triangle at a time.
  void triangles(const Leaf& leaf, uint32_t mask, const RayPacket& p, const PacketSetup<Kernel>& ps,
                 std::span<const Ray> rays, uint32_t inst) {
    const typename Kernel::Block kb{LeafView(leaf)};
    const typename Kernel::Origins og(kb, ps.kbeam);
    if (by_rays(mask, leaf.n)) {
      closest_by_rays<Kernel>(leaf, kb, og, mask, p, rays, h, inst);
      return;
    }
    for (uint32_t k = 0; k < leaf.n; ++k)
      take_closest(h, ps.kp.test(typename Kernel::Triangle(kb, k, og), h.tfar, mask), mask, leaf.prim(k), inst);
  }
};

// ---- any hit ----

/// Whether anything occludes one ray within [tnear, tfar].
template <class Kernel>
struct AnySingle {
  static constexpr bool kNearFirst = false;
  float tfar;
  bool found = false;
  explicit AnySingle(const Ray& r) : tfar(r.tfar) {}
  bool done() const { return found; }
  bool analytic(const Scene& scene, uint32_t id, const Ray& r) { return found = scene.intersect_analytic(id, r).hit; }
  RP_SIMD_INLINE bool triangles(const Leaf& leaf, const typename Kernel::Block& kb, const typename Kernel::Single& kr,
                                uint32_t /*inst*/) {
    return found = (simd::movemask(kr.block(kb, float8(tfar)).hit) & ((1u << leaf.n) - 1)) != 0;
  }
};

/// Which lanes of an 8-ray packet are occluded (`done`) among the lanes `lanes` traced.
template <class Kernel>
struct AnyPacket {
  using Single = AnySingle<Kernel>;
  const float8& tfar_;
  uint32_t lanes;
  uint32_t done = 0;
  AnyPacket(const float8& tfar, uint32_t traced) : tfar_(tfar), lanes(traced) {}
  bool live() const { return (lanes & ~done) != 0; }
  uint32_t pending(uint32_t mask) const { return mask & ~done; }
  const float8& tfar() const { return tfar_; }
  template <class F>
  void each_single(uint32_t mask, std::span<const Ray> rays, F&& f) {
    for (uint32_t b = mask; b; b &= b - 1) {
      const Ray& r = rays[size_t(std::countr_zero(b))];
      Single s(r);
      f(r, s);
      if (s.found) done |= b & (~b + 1);
    }
  }
  /// The query of the lanes `valid` in an instance's object space, with their tfar there.
  AnyPacket object(uint32_t valid, const float8& tfar) const { return {tfar, valid}; }
  void join(const AnyPacket& o) { done |= o.done; }
  void analytic(const Scene& scene, uint32_t id, std::span<const Ray> rays, uint32_t mask) {
    done |= any_analytic(scene, id, rays, mask);
  }
  void triangles(const Leaf& leaf, uint32_t mask, const RayPacket&, const PacketSetup<Kernel>& ps, std::span<const Ray>,
                 uint32_t /*inst*/) {
    const typename Kernel::Block kb{LeafView(leaf)};
    for (uint32_t k = 0; k < leaf.n && mask; ++k) {
      const uint32_t hit = simd::movemask(ps.kp.test(typename Kernel::Triangle(kb, k), tfar_, mask).hit) & mask;
      done |= hit;
      mask &= ~hit;
    }
  }
};

// ---- queries whose hits pass a gate (masks and filters), and every hit ----

/// Calls f(hit) for the triangles of `leaf` (read into `kb`) that the ray (set up in `kr`)
/// hits within [tnear, tfar], nearest first (ties by prim_id), until f returns true.
template <class Kernel, class F>
RP_SIMD_INLINE bool each_triangle_hit(const Leaf& leaf, const typename Kernel::Block& kb,
                                      const typename Kernel::Single& kr, float tfar, uint32_t inst, F&& f) {
  const TriHit8 h = kr.block(kb, float8(tfar));
  uint32_t bits = simd::movemask(h.hit) & ((1u << leaf.n) - 1);
  if (!bits) return false;
  alignas(32) float t[8], u[8], v[8];
  h.t.store_aligned(t);
  h.u.store_aligned(u);
  h.v.store_aligned(v);
  while (bits) {
    int lane = std::countr_zero(bits);
    for (uint32_t b = bits & (bits - 1); b; b &= b - 1) {
      const int c = std::countr_zero(b);
      if (t[c] < t[lane] || (t[c] == t[lane] && leaf.prim(uint32_t(c)) < leaf.prim(uint32_t(lane)))) lane = c;
    }
    bits &= ~(1u << lane);
    if (f(Hit{t[lane], leaf.prim(uint32_t(lane)), u[lane], v[lane], inst})) return true;
  }
  return false;
}

/// The closest hit of one ray that `gate` lets through (a HitGate, core/backend.h).
template <class Kernel, class Gate>
struct GatedClosest {
  static constexpr bool kNearFirst = true;
  const Gate& gate;
  Hit best;
  float tfar;
  GatedClosest(const Ray& r, const Gate& g) : gate(g), tfar(r.tfar) {}
  static constexpr bool done() { return false; }
  /// Takes `h` when it is closer (or as close and first by the rule of levels.h) and passes.
  bool offer(const Hit& h) {
    if (h.t > tfar || (h.t == tfar && best.hit() && !before(h.prim_id, h.instance_id, best))) return false;
    if (!gate(h)) return false;
    best = h;
    tfar = h.t;
    return true;
  }
  bool analytic(const Scene& scene, uint32_t id, const Ray& r) {
    for_each_analytic_hit(scene, id, r, kNoInstance, [&](const Hit& h) { return offer(h); });
    return false;
  }
  RP_SIMD_INLINE bool triangles(const Leaf& leaf, const typename Kernel::Block& kb, const typename Kernel::Single& kr,
                                uint32_t inst) {
    each_triangle_hit<Kernel>(leaf, kb, kr, tfar, inst, [&](const Hit& h) { return offer(h); });
    return false;
  }
};

/// Whether one ray hits anything that `gate` lets through.
template <class Kernel, class Gate>
struct GatedAny {
  static constexpr bool kNearFirst = false;
  const Gate& gate;
  float tfar;
  bool found = false;
  GatedAny(const Ray& r, const Gate& g) : gate(g), tfar(r.tfar) {}
  bool done() const { return found; }
  bool analytic(const Scene& scene, uint32_t id, const Ray& r) {
    return found = for_each_analytic_hit(scene, id, r, kNoInstance, gate);
  }
  RP_SIMD_INLINE bool triangles(const Leaf& leaf, const typename Kernel::Block& kb, const typename Kernel::Single& kr,
                                uint32_t inst) {
    return found = each_triangle_hit<Kernel>(leaf, kb, kr, tfar, inst, gate);
  }
};

/// Every hit of one ray within [tnear, tfar] that `gate` lets through, appended to `out` (in
/// the order of the visits; a triangle in several leaves of a spatial-split tree, more than
/// once).
template <class Kernel, class Gate>
struct Every {
  static constexpr bool kNearFirst = false;
  const Gate& gate;
  std::vector<Hit>& out;
  float tfar;
  Every(const Ray& r, const Gate& g, std::vector<Hit>& o) : gate(g), out(o), tfar(r.tfar) {}
  static constexpr bool done() { return false; }
  bool keep(const Hit& h) {
    if (gate(h)) out.push_back(h);
    return false;
  }
  bool analytic(const Scene& scene, uint32_t id, const Ray& r) {
    for_each_analytic_hit(scene, id, r, kNoInstance, [&](const Hit& h) { return keep(h); });
    return false;
  }
  RP_SIMD_INLINE bool triangles(const Leaf& leaf, const typename Kernel::Block& kb, const typename Kernel::Single& kr,
                                uint32_t inst) {
    each_triangle_hit<Kernel>(leaf, kb, kr, tfar, inst, [&](const Hit& h) { return keep(h); });
    return false;
  }
};

}  // namespace rp::bvh8
