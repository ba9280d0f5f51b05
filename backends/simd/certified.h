#pragma once
/// The triangle test of the watertight variant: Möller–Trumbore ×8 (the default variant's
/// kernel) with a forward error bound on each of its decisions, and the watertight test of
/// Woop, Benthin and Wald (2013) for the lanes whose decisions the bound leaves uncertain.
/// AVX2+FMA translation units only.
///
/// Why the combination is watertight. For an edge p-q and a ray (o, d), let E be the exact
/// determinant det(p - o, q - o, d): its sign says on which side of the edge's line the ray
/// passes. Möller–Trumbore's U, V and W = |den| - U - V are, in exact arithmetic, the E of
/// the triangle's three edges (signed by den), and Woop's three 2D edge functions are E / d_kz.
/// B bounds, for each edge, the error of Möller–Trumbore's value plus the error Woop's test
/// makes on the same quantity. A lane is certain of its edges when all three values lie
/// farther than B from 0 (both tests then see the sign of every exact E, so both pass the
/// edges or both miss), or when one lies below -3.5B (both see that edge negative and, as the
/// three exact values sum to |den|, another positive: mixed signs, a miss in both). A lane
/// inside the triangle must also have its t farther from tnear than the sum of both tests' t
/// errors, so that both compare it alike (a ray leaving a surface meets its own triangle
/// there). Every other lane is decided by Woop's test itself. So every lane's hit or miss is
/// Woop's, but for one case: a lane inside whose t lies within those errors of tfar is
/// compared with tfar by Möller–Trumbore. Such a hit is a near-tie with the hit that set tfar
/// (or lies at the end of the ray's segment), never a ray through a mesh; deciding it by
/// Woop's test would make which test reported a hit, and so the bits of its t, depend on the
/// order in which a traversal met the leaves, where now every path gives the same bits. So
/// two triangles sharing an edge, however each lane was decided, reach the decisions of Woop's
/// watertight test, which computes a shared edge's function from the same floats for both and
/// never lets a ray through. (A property test compares every lane with the unfiltered test on
/// rays aimed at shared edges and vertices, near them, and leaving a surface.) Only t, u, v of
/// a certain hit come from Möller–Trumbore.
///
/// The bound, per lane, with max-abs norms, u = 2^-24, c = v0 - o and r = c x d as
/// Möller–Trumbore computes them, M = |c|, R' = |r| + 2^-20 M D, D = |d| (= |d_kz|) and X the
/// triangle's edge bound (edge_bound8: the exact |e1|, |e2| <= X):
///
///     B = u (R' + 2.2 X D) (38 M + 94 X).
///
/// Möller–Trumbore's errors, each rounded difference, product and FMA of its factoring traced
/// (r and Ng = e2 x e1 per component within 6.5u M D and 8u X^2): U and V within
/// u X (20.2 M D + 14 R'), |den| within 52.7u D X^2, T = Ng.c within 52.7u M X^2, W within
/// u X (53.2 X D + 40.7 M D + 35.1 R'). Woop's, in the units of E: a vertex's sheared
/// coordinates err by at most s = u (4.5 (M + X) + 1.1 P / D) and lie within P / D of 0,
/// P = R' + 2.01 X D >= |(p - o) x d|; an edge function errs by at most
/// 2.01 (2 P s + s^2 D) + 4.5u P^2 / D <= u (36 R' M + 54 R' X + 36.4 X D M + 72.4 X^2 D)
/// (R' / D <= 2.01 M). The sum, u (36 R' M + 89 R' X + 77 X D M + 126 X^2 D), is below each
/// term of B's product (38, 94, 83.6, 206.8) with room for the bound's own rounding.
///
/// t, for a lane inside (each edge value above B, so |den| >= 3B): both tests' denominators
/// exceed den_lo = |den| (1 - 2^-22) - 3.5B. Möller–Trumbore's t errs by at most
/// 63.2u X^2 (M + |t| D) / (D den_lo) + 2.2u |t| (|t| of the exact t within 1.2 times the
/// computed one's bound); Woop's t is the average of the vertices' depths z_i weighted by its
/// edge functions, so it errs by at most sum |dE_i| |z_i - t| / det <= 6.1 B X / (D den_lo),
/// plus the depths' roundings 6u (M + X) / D and 4u |t|. With the comparisons' own roundings
/// the sum stays below [B (6.9 X + 0.47 |t| D) + 14u (M + X + |t| D) |den|] / (D den_lo), so a
/// lane inside is certain when |t - tnear| exceeds that.
///
/// No term underflows, which could hide an error: valid rays have D >= 2^-26, and X >= 2^-32.
/// Lanes past a leaf's end are NaN: every comparison is false, the lane counts as certain,
/// and Möller–Trumbore's miss is Woop's miss too.

#include <bit>
#include <cstdint>
#include <limits>
#include <span>

#include "backends/simd/kernels.h"
#include "engine/geometry/triangle.h"

namespace rp::bvh8 {

/// Max-abs norm of each lane.
RP_SIMD_INLINE float8 max_abs(const Vec3x8& a) {
  return xsimd::max(xsimd::abs(a.x), xsimd::max(xsimd::abs(a.y), xsimd::abs(a.z)));
}

/// The edge bound X of each lane's triangle from its rounded edges e1, e2 (as the kernels
/// compute them from the leaf's vertices): the largest |coordinate| times 1 + 2^-22, which
/// covers the rounding of the edges (|exact| <= |rounded| (1 + 2^-23)) and of the product, and
/// at least 2^-32. Per lane rather than stored: no leaf bytes, and tighter where a leaf mixes
/// large and small triangles; the same speed as a word per leaf (measured, see the README).
RP_SIMD_INLINE float8 edge_bound8(const Vec3x8& e1, const Vec3x8& e2) {
  return xsimd::max(float8(0x1p-32f), xsimd::max(max_abs(e1), max_abs(e2)) * float8(1.0f + 0x1p-22f));
}

/// Rays for the certified test: one ray broadcast or the 8 of a packet, with the per-ray
/// figures of the bounds.
struct CertifiedRays {
  Vec3x8 org, dir;
  float8 tnear;
  float8 d;          ///< D = |dir|
  float8 d_m;  ///< 2^-20 D
  float8 d_x;  ///< 2.2 D, the factor of X in the edge bound
  float8 d_t;  ///< 0.47 D, the factor of |t| B in the t bound

  CertifiedRays() = default;
  /// The 8 rays of a packet.
  RP_SIMD_INLINE CertifiedRays(const Vec3x8& o, const Vec3x8& dir_, const float8& tn)
      : org(o), dir(dir_), tnear(tn), d(max_abs(dir_)), d_m(d * float8(0x1p-20f)), d_x(d * float8(2.2f)),
        d_t(d * float8(0.47f)) {}
  /// One ray in every lane (no 8-wide work: the ray-stream traversal sets one up per leaf).
  RP_SIMD_INLINE explicit CertifiedRays(const Ray& r)
      : CertifiedRays(r, max_component(abs(r.dir))) {}

 private:
  RP_SIMD_INLINE CertifiedRays(const Ray& r, float d_)
      : org(r.org), dir(r.dir), tnear(r.tnear), d(d_), d_m(d_ * 0x1p-20f), d_x(d_ * 2.2f), d_t(d_ * 0.47f) {}
};

/// Möller–Trumbore on triangles v0, e1 = v0 - v1, e2 = v2 - v0, Ng = e2 x e1 (cross_fma) with
/// edge bound `x`: its answer in `h` (the bits of moller_trumbore8); returns the lanes whose
/// decisions its bounds leave uncertain (see the top of this file).
RP_SIMD_INLINE uint32_t certified_mt8(const CertifiedRays& r, const float8& tfar, const Vec3x8& v0, const Vec3x8& e1,
                                      const Vec3x8& e2, const Vec3x8& ng, const float8& x, TriHit8& h) {
  const MtTerms m = mt_terms(r.org, r.dir, v0, e1, e2, ng);
  h = mt_answer(m, r.tnear, tfar);
  const mask8 edges = mt_edges(m);

  const float8 mc = max_abs(m.c);
  const float8 rr = xsimd::fma(mc, r.d_m, max_abs(m.r));  // R' = R + 2^-20 M D
  const float8 b = (rr + x * r.d_x) * xsimd::fma(mc, float8(38.0f * 0x1p-24f), x * float8(94.0f * 0x1p-24f));
  const float8 w = m.abs_den - (m.u + m.v);
  const float8 least = xsimd::min(xsimd::abs(m.u), xsimd::min(xsimd::abs(m.v), xsimd::abs(w)));
  const float8 lowest = xsimd::min(m.u, xsimd::min(m.v, w));
  // Not sure of the edges: some value within B of 0, and none below -3.5B. A NaN lane (past a
  // leaf's end; no other lane can have one) compares false: certain, Möller–Trumbore's miss.
  const mask8 unsure_edges = (least <= b) & (lowest >= b * float8(-3.5f));
  // t, where the ray passes inside: |t - t_exact| D (|den| - 3.5B) <= rhs for both tests. Only
  // tnear is checked (see the top of this file on tfar).
  const float8 at = xsimd::abs(h.t);
  const float8 rhs = xsimd::fma(b, xsimd::fma(at, r.d_t, x * float8(6.9f)),
                                xsimd::fma(at, r.d, mc + x) * (m.abs_den * float8(14.0f * 0x1p-24f)));
  const float8 den_d = xsimd::fms(m.abs_den, float8(1.0f - 0x1p-22f), b * float8(3.5f)) * r.d;
  const mask8 unsure_t = edges & ~(xsimd::abs(h.t - r.tnear) * den_d > rhs);  // NaN: unsure
  return simd::movemask(unsure_edges | unsure_t);
}

/// Woop's answers (watertight8: the bits of the scalar routine) for the lanes `unsure`.
struct Settled {
  TriHit8 w;
  /// Replaces the lanes `unsure` of `h` by these.
  RP_SIMD_INLINE void merge_into(TriHit8& h, uint32_t unsure) const {
    const mask8 m = simd::mask_from_bits(unsure);
    h.hit = (w.hit & m) | (h.hit & ~m);
    h.t = xsimd::select(m, w.t, h.t);
    h.u = xsimd::select(m, w.u, h.u);
    h.v = xsimd::select(m, w.v, h.v);
  }
};

/// Woop's test for one ray against the triangles of `leaf`. Out of line and cold: inlined, it
/// would make the traversal around the kernel keep its vectors in memory (bunny diffuse rays
/// 20% slower, though it ran for 0.3% of leaf tests).
[[gnu::noinline, gnu::cold]] inline void settle_single(const Leaf& leaf, const Ray& ray, float tfar, Settled& out) {
  const LeafView lv(leaf);
  out.w = watertight8(WatertightRays(ray), lv.v0, lv.v1, lv.v2, float8(tfar));
}

/// Woop's per-ray set-up of a packet's 8 rays, made the first time a lane needs Woop's test.
struct LazyWatertightRays {
  WatertightRays rays;
  bool ready = false;
};

/// The same for the 8 rays of a packet (`rays`, as the packet was loaded from) against one
/// triangle (a, b, c).
[[gnu::noinline, gnu::cold]] inline void settle_packet(std::span<const Ray> rays, LazyWatertightRays& wr,
                                                       const float8& tfar, const Vec3f& a, const Vec3f& b,
                                                       const Vec3f& c, Settled& out) {
  if (!wr.ready) wr = {WatertightRays(rays.data(), rays.size()), true};
  out.w = watertight8(wr.rays, Vec3x8(a), Vec3x8(b), Vec3x8(c), tfar);
}

}  // namespace rp::bvh8
