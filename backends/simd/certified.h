#pragma once
/// The triangle test of the watertight variant: Möller–Trumbore ×8 (the default variant's
/// kernel) with a forward error bound on each of its edge decisions, and the watertight test
/// of Woop, Benthin and Wald (2013) for the lanes whose decisions the bound leaves uncertain.
/// AVX2+FMA translation units only.
///
/// Why the combination is watertight. For an edge p-q and a ray (o, d), let E be the exact
/// determinant det(p - o, q - o, d): its sign says on which side of the edge's line the ray
/// passes. Möller–Trumbore's U, V and W = |den| - U - V are, in exact arithmetic, the E of
/// the triangle's three edges (signed by den), and Woop's three 2D edge functions are E / d_kz.
/// B bounds, for each edge, the error of Möller–Trumbore's value plus the error Woop's test
/// makes on the same quantity, so where Möller–Trumbore's value lies farther than B from 0,
/// both tests see that edge's exact E with its sign. A lane is certain of its edges when all
/// three values exceed B (both tests see the three E with one sign: both pass), or when one
/// lies below -B and another above B (both see two E of opposite signs, whatever they see of
/// the third: both miss; should Woop's test find the third exactly 0, it re-evaluates all three
/// in double from the same sheared coordinates, with less rounding than in float, and the two
/// keep their signs). Every other lane, a ray within about B of the triangle's border or nearly
/// parallel to it, is decided by Woop's test itself. So every lane passes or fails its edges as
/// Woop's test does: two triangles sharing an edge, however each lane was decided, reach the
/// decisions of Woop's watertight test, which computes a shared edge's function from the same
/// floats for both and never lets a ray through. (A property test compares every lane with the
/// unfiltered test on rays aimed at shared edges and vertices, near them, and leaving a
/// surface.)
///
/// The distance of a certain lane, and so its comparisons with tnear and tfar, are
/// Möller–Trumbore's, as are its u, v. That is not a leak: a ray whose t lies within rounding
/// of tnear or tfar has its hit at the end of its segment (a ray leaving its own surface, or a
/// near-tie with the hit that set tfar), where both tests decide by a rounded t and
/// Möller–Trumbore's is the more accurate one (tested against a double reference, and on rays
/// leaving a surface its decision agrees with the reference's at least as often as Woop's). A
/// rigorous bound on both tests' t error, tried first, was some thousands of u X wide: wider
/// than the renderer's ray-origin offset on large triangles, it sent 8.6% of Sponza's shadow
/// lanes (43% of leaf tests) to the slow path. Deciding by Möller–Trumbore also keeps the bits
/// of a reported t independent of the order in which a traversal met the leaves.
///
/// One guard keeps a hit's t as accurate as Woop's where Möller–Trumbore's is not: a lane inside
/// Möller–Trumbore's edges with |den| < 2^-12 X^2 D (kThin) goes to Woop's test too, whatever
/// its t (so the guard need not wait for t's division). Möller–Trumbore's t is Ng.c / Ng.d, and
/// on a needle (or a ray nearly in the triangle's plane) Ng is the cross product of nearly
/// parallel edges, relatively far less accurate than the edges; Woop's t is the average of the
/// vertices' depths weighted by its edge functions and does not depend on Ng. (Tested on
/// needles and near-degenerate triangles against the double test: without the guard the
/// kernel's t is wrong more often than Woop's.)
///
/// The bound, per lane, with max-abs norms, u = 2^-24, c = v0 - o and r = c x d as
/// Möller–Trumbore computes them, M = |c|, R' = |r| + 2^-20 M D, D = |d| (= |d_kz|) and X the
/// triangle's edge bound (edge_bound8: the exact |e1|, |e2| <= X):
///
///     B = u (R' + 2.2 X D) (38 M + 94 X).
///
/// Möller–Trumbore's errors, each rounded difference, product and FMA of its factoring traced
/// (r and Ng = e2 x e1 per component within 6.5u M D and 8u X^2): U and V within
/// u X (20.2 M D + 14 R'), |den| within 52.7u D X^2, W within u X (53.2 X D + 40.7 M D +
/// 35.1 R'). Woop's, in the units of E: a vertex's sheared coordinates err by at most
/// s = u (4.5 (M + X) + 1.1 P / D) and lie within P / D of 0, P = R' + 2.01 X D >=
/// |(p - o) x d|; an edge function errs by at most 2.01 (2 P s + s^2 D) + 4.5u P^2 / D <=
/// u (36 R' M + 54 R' X + 36.4 X D M + 72.4 X^2 D) (R' / D <= 2.01 M). The sum,
/// u (36 R' M + 89 R' X + 77 X D M + 126 X^2 D), is below each term of B's product (38, 94,
/// 83.6, 206.8) with room for the bound's own rounding.
///
/// No term underflows, which could hide an error: valid rays have D >= 2^-26, and X >= 2^-32.
/// Lanes past a leaf's end are NaN: every comparison is false, the lane counts as certain,
/// and Möller–Trumbore's miss is Woop's miss too.

#include <cstdint>

#include "backends/simd/kernels.h"
#include "engine/geometry/triangle.h"

namespace rp::bvh8 {

/// The |den| (in units of X^2 D) below which a lane inside the edges is left to Woop's test.
inline constexpr float kThin = 0x1p-12f;

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

/// One ray for the certified test, broadcast, with the per-ray factors of the bound.
struct CertifiedRays {
  Vec3x8 org, dir;
  float8 tnear;
  float8 d;  ///< D = |dir| (max-norm), the ray's factor in the bound

  CertifiedRays() = default;
  /// From SoA vectors (a packet's lane, broadcast).
  RP_SIMD_INLINE CertifiedRays(const Vec3x8& o, const Vec3x8& dir_, const float8& tn)
      : org(o), dir(dir_), tnear(tn), d(max_abs(dir_)) {}
  /// One ray in every lane (its factors computed on the broadcast direction: the same bits as
  /// from the scalar norm, in fewer instructions).
  RP_SIMD_INLINE explicit CertifiedRays(const Ray& r) : CertifiedRays(Vec3x8(r.org), Vec3x8(r.dir), float8(r.tnear)) {}
};

/// A triangle's factors of the bound, from its edge bound X (edge_bound8): 2.2 X, 94u X and
/// 2^-12 X^2 (kThin). Computed once per triangle where many rays meet it.
struct EdgeFactors {
  float8 x22, x94, x_thin;
  EdgeFactors() = default;
  /// Lane k of `f` in every lane.
  RP_SIMD_INLINE EdgeFactors(const EdgeFactors& f, int k)
      : x22(simd::broadcast_lane(f.x22, k)),
        x94(simd::broadcast_lane(f.x94, k)),
        x_thin(simd::broadcast_lane(f.x_thin, k)) {}
  RP_SIMD_INLINE explicit EdgeFactors(const float8& x)
      : x22(x * float8(2.2f)), x94(x * float8(94.0f * 0x1p-24f)), x_thin(x * x * float8(kThin)) {}
};

/// Möller–Trumbore's answer from its terms `m` for rays of max-norms `d` (CertifiedRays), with
/// the certified rule, given the bound's factors from M >= |c| per lane, g = 2^-20 M + 2.2 X
/// (bound_g) and q = 38u M + 94u X (bound_q), so that B = (R + D g) q: the answer in `h`
/// (the bits of moller_trumbore8 on every lane the rule leaves certain), and as the result the
/// lanes whose edge decisions the bound leaves uncertain, and the lanes nearly in the
/// triangle's plane inside its edges (see the top of this file).
RP_SIMD_INLINE uint32_t certified_answer(const MtTerms& m, const float8& g, const float8& q, const float8& d,
                                         const float8& tnear, const float8& tfar, const EdgeFactors& f, TriHit8& h) {
  const float8 b = xsimd::fma(d, g, max_abs(m.r)) * q;  // (R' + 2.2 X D) q, R' = R + 2^-20 M D
  const float8 w = m.abs_den - (m.u + m.v);
  const float8 lowest = xsimd::min(m.u, xsimd::min(m.v, w));
  const float8 highest = xsimd::max(m.u, xsimd::max(m.v, w));
  // Inside Möller–Trumbore's edges: U, V >= 0 and U + V <= |den| (the sign of |den| - (U + V)
  // is exact), as mt_edges decides it but for den != 0, which mt_answer's t test implies. A
  // NaN lane (past a leaf's end; no other lane can have one) is outside (MINPS returns its
  // second operand on a NaN, and all three are NaN there).
  const mask8 inside = lowest >= float8(0.0f);
  h = mt_answer(m, inside, tnear, tfar);
  // Sure of the edges: every value above B, or one below -B and another above B; that is
  // min(highest, |lowest|) > B (B > 0: the lowest value's sign is sure and the highest is
  // above B, so either all three are or two have opposite signs; no rounding: abs, min and max
  // are exact). A NaN lane compares false: certain, Möller–Trumbore's miss.
  const float8 reach = xsimd::min(highest, xsimd::abs(lowest));
  // A lane inside the edges nearly in the triangle's plane or on a needle (|den| < 2^-12 X^2 D)
  // goes to Woop's test too, whatever its t: see the top of this file.
  const mask8 thin = inside & (m.abs_den < f.x_thin * d);
  return simd::movemask((reach <= b) | thin);
}

/// The bound's factor of D, 2^-20 M + 2.2 X, for M >= |c|.
RP_SIMD_INLINE float8 bound_g(const float8& mc, const EdgeFactors& f) {
  return xsimd::fma(mc, float8(0x1p-20f), f.x22);
}

/// The bound's second factor, 38u M + 94u X, for M >= |c|.
RP_SIMD_INLINE float8 bound_q(const float8& mc, const EdgeFactors& f) {
  return xsimd::fma(mc, float8(38.0f * 0x1p-24f), f.x94);
}

/// Möller–Trumbore on rays (org, dir, tnear) of max-norms `d` (CertifiedRays) and triangles
/// v0, e1 = v0 - v1, e2 = v2 - v0, Ng = e2 x e1 (cross_fma) with edge factors `f`: its answer
/// in `h` (the bits of moller_trumbore8); returns the lanes it leaves to Woop's test
/// (certified_answer), M taken lane by lane.
RP_SIMD_INLINE uint32_t certified_mt8(const Vec3x8& org, const Vec3x8& dir, const float8& tnear, const float8& d,
                                      const float8& tfar, const Vec3x8& v0, const Vec3x8& e1, const Vec3x8& e2,
                                      const Vec3x8& ng, const EdgeFactors& f, TriHit8& h) {
  const MtTerms m = mt_terms(org, dir, v0, e1, e2, ng);
  const float8 mc = max_abs(m.c);
  return certified_answer(m, bound_g(mc, f), bound_q(mc, f), d, tnear, tfar, f, h);
}

/// The same with the factors g = bound_g(M) and q = bound_q(M) given (SharedOrigin: rays from
/// one point).
RP_SIMD_INLINE uint32_t certified_mt8(const Vec3x8& org, const Vec3x8& dir, const float8& tnear, const float8& d,
                                      const float8& tfar, const Vec3x8& v0, const Vec3x8& e1, const Vec3x8& e2,
                                      const Vec3x8& ng, const EdgeFactors& f, const float8& g, const float8& q,
                                      TriHit8& h) {
  return certified_answer(mt_terms(org, dir, v0, e1, e2, ng), g, q, d, tnear, tfar, f, h);
}

/// The same for one ray broadcast (CertifiedRays).
RP_SIMD_INLINE uint32_t certified_mt8(const CertifiedRays& r, const float8& tfar, const Vec3x8& v0, const Vec3x8& e1,
                                      const Vec3x8& e2, const Vec3x8& ng, const EdgeFactors& f, TriHit8& h) {
  return certified_mt8(r.org, r.dir, r.tnear, r.d, tfar, v0, e1, e2, ng, f, h);
}

/// M for the triangles of a leaf (lanes) and rays that all start at one point, as a pinhole
/// camera's primary rays do: c = v0 - o is then the same floats for every ray, and so is M,
/// computed here once for all of them with the bound's factors from it (the same bits as each
/// ray's own: every answer stays the one-ray test's). `shared` when the box of the rays'
/// origins (a packet's or a group's beam, mirrored per axis as PacketBeam keeps it) is one
/// point.
struct SharedOrigin {
  float8 g, q;  ///< bound_g(M) and bound_q(M) per triangle, when `shared`
  bool shared = false;
  RP_SIMD_INLINE SharedOrigin(const Vec3x8& v0, const EdgeFactors& f, const PacketBeam& beam) {
    if (!beam.valid) return;
    float o[3];
    for (int a = 0; a < 3; ++a) {
      const float lo = beam.omin[a].get(0);
      if (lo != beam.omax[a].get(0)) return;
      o[a] = beam.neg[a] ? -lo : lo;  // (a -0 and a +0 origin give the same |c|)
    }
    const float8 m = max_abs(v0 - Vec3x8(Vec3f{o[0], o[1], o[2]}));
    g = bound_g(m, f);
    q = bound_q(m, f);
    shared = true;
  }
};

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

/// The same for the 8 rays of a packet (SoA, as loaded) against triangle k of `leaf`. Woop's
/// set-up of the rays is made here, 8 lanes at once, each time: keeping it in the packet made
/// the large-packet traversal's working set twice as large.
[[gnu::noinline, gnu::cold]] inline void settle_packet(const RayPacket& p, const float8& tfar, const Leaf& leaf,
                                                       uint32_t k, Settled& out) {
  out.w = watertight8(WatertightRays(p.org, p.dir, p.tnear), Vec3x8(leaf.vertex(k, 0)), Vec3x8(leaf.vertex(k, 1)),
                      Vec3x8(leaf.vertex(k, 2)), tfar);
}

}  // namespace rp::bvh8
