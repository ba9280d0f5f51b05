#pragma once
/// The triangle test of the watertight variant: Möller–Trumbore ×8 (the default variant's
/// kernel) with a forward error bound on each of its edge decisions, and exact edge decisions
/// (rp::edge_side, core/geometry/exact_triangle.h) for the lanes the bound leaves uncertain.
/// AVX2+FMA translation units only.
///
/// Why the combination is watertight. For an edge p-q and a ray (o, d), let E be the exact
/// determinant ((p - o) x (q - o)) . d: its sign says on which side of the edge's line the ray
/// passes. Möller–Trumbore's U, V and W = |den| - U - V are, in exact arithmetic, the E of
/// the triangle's edges (v2, v0), (v0, v1) and (v1, v2), signed by den. B bounds the error of
/// each of Möller–Trumbore's three values, so where a value lies farther than B from 0 its sign
/// is that of the exact E. A lane is certain of its edges when all three values exceed B (the
/// three E have one sign: inside), or when one lies below -B and another above B (two E of
/// opposite signs: outside). Every other lane, a ray within about B of an edge's line or
/// nearly parallel to the triangle, is decided exactly with the sign of each uncertain E taken
/// exactly. So every lane passes or fails its edges as the exact signs say: two
/// triangles sharing an edge see one determinant for it (negated), the triangles around a
/// shared vertex see the ray on consistent sides of their edges, and no ray that crosses a
/// closed mesh passes between its triangles, at any translation or scale. (A property test
/// compares every lane with rp::intersect_triangle_exact on rays aimed at shared edges and
/// vertices, near them, and leaving a surface.)
///
/// The distance of a certain lane, and so its comparisons with tnear and tfar, are
/// Möller–Trumbore's, as are its u, v. That is not a leak: a ray whose t lies within rounding
/// of tnear or tfar has its hit at the end of its segment (a ray leaving its own surface, or a
/// near-tie with the hit that set tfar), where any test decides by a rounded t. A rigorous
/// bound on the t error, tried first, was some thousands of u X wide: wider than the
/// renderer's ray-origin offset on large triangles, it sent many of Sponza's shadow lanes to the
/// slow path (figures: docs/notes/2026-11-29-figures-from-code-comments.md). Deciding by
/// Möller–Trumbore also keeps the bits of a reported t independent of the order in which a
/// traversal met the leaves.
///
/// One guard keeps a hit's t accurate where Möller–Trumbore's is not: a lane inside
/// Möller–Trumbore's edges with |den| < 2^-12 X^2 D (kThin) is decided exactly too, whatever its t (so
/// the guard need not wait for t's division), by rp::intersect_triangle_exact, which computes t
/// in double. (Rays from one point take one threshold for the beam, at least each ray's; the
/// exact decision then decides by the lane's own.)
/// Möller–Trumbore's t is Ng.c / Ng.d, and on a needle (or a ray nearly in the triangle's
/// plane) Ng is the cross product of nearly parallel edges, relatively far less accurate than
/// the edges. (Tested on needles and near-degenerate triangles against the double test:
/// without the guard the kernel's t is wrong more often than the float watertight test's.)
///
/// The bound, per lane, with max-abs norms, u = 2^-24, c = v0 - o as Möller–Trumbore computes
/// it, M = |c|, D = |d| (= |d_kz|) and X the triangle's edge bound (edge_bound8: the exact
/// |e1|, |e2| <= X):
///
///     B = u X D (116 M + 56 X),
///
/// and for rays from one point (SharedOrigin, where M is taken once per triangle), with
/// R = |c x d| as computed, the tighter B = u X (36 R + 41 M D + 54 X D). The traversals take
/// R there at its largest over the beam of rays that meets a leaf (rho, SharedOrigin): one
/// FMA a test, B = D h + g, with h and g made once per leaf.
///
/// Möller–Trumbore's errors, each rounded difference, product and FMA of its factoring traced
/// (r = c x d and Ng = e2 x e1 per component within 6.5u M D and 8u X^2): U and V within
/// u X (20.2 M D + 14 R'), |den| within 52.7u D X^2, W within u X (53.2 X D + 40.7 M D +
/// 35.1 R'), where R' = R + 2^-20 M D. W's bound is the widest, and both forms of B exceed it
/// with room for their own few roundings: the second directly; the first because each
/// component of a cross product is at most twice the product of its factors' max-norms, so
/// R' <= 2.0001 M D and W's bound is at most u X D (110.9 M + 53.2 X). The second, where M is
/// shared, leaves about a third as many lanes uncertain on camera rays. Which one a path takes
/// changes nothing in its answers (below), only how often it decides exactly.
///
/// The exact decision (Uncertain) makes the test's terms again for its lanes and decides each edge by
/// Möller–Trumbore's value where that lies farther than the first form of B from 0, and by
/// rp::edge_side, exactly, otherwise; inside the edges its t, u, v are Möller–Trumbore's (u, v
/// clamped to the triangle), or, for a lane with |den| < 2^-12 X^2 D, rp::intersect_triangle_exact's
/// (t in double). Those are the answers of a certain lane too, so every lane's answer, certain
/// or decided exactly, on whichever path, is the same function of the ray and the triangle: a packet,
/// a ray alone and rays from one point give the same bits.
///
/// No term underflows, which could hide an error: valid rays have D >= 2^-26, and X >= 2^-32,
/// so B >= 2^-108. Lanes past a leaf's end are NaN: every comparison is false, the lane
/// counts as certain, and Möller–Trumbore's miss is the exact miss too.

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <span>

#include "backends/simd/moller_trumbore.h"
#include "core/geometry/exact_triangle.h"

namespace rp::bvh8 {

/// The |den| (in units of X^2 D) below which a lane inside the edges is decided exactly, t in double.
inline constexpr float kThin = 0x1p-12f;

/// The edge bound X of each lane's triangle from its rounded edges e1, e2 (as the kernels
/// compute them from the leaf's vertices): the largest |coordinate| times 1 + 2^-22, which
/// covers the rounding of the edges (|exact| <= |rounded| (1 + 2^-23)) and of the product, and
/// at least 2^-32. Per lane rather than stored: no leaf bytes, and tighter where a leaf mixes
/// large and small triangles; the same speed as a word per leaf (measured, see the README).
RP_SIMD_INLINE float8 edge_bound8(const Vec3x8& e1, const Vec3x8& e2) {
  return xsimd::max(float8(0x1p-32f), xsimd::max(max_abs(e1), max_abs(e2)) * float8(1.0f + 0x1p-22f));
}

/// One ray for the watertight test, broadcast, with the per-ray factors of the bound.
struct WatertightRays {
  Vec3x8 org, dir;
  float8 tnear;
  float8 d;  ///< D = |dir| (max-norm), the ray's factor in the bound

  WatertightRays() = default;
  /// From SoA vectors (a packet's lane, broadcast).
  RP_SIMD_INLINE WatertightRays(const Vec3x8& o, const Vec3x8& dir_, const float8& tn)
      : org(o), dir(dir_), tnear(tn), d(max_abs(dir_)) {}
  /// One ray in every lane (its factors computed on the broadcast direction: the same bits as
  /// from the scalar norm, in fewer instructions).
  RP_SIMD_INLINE explicit WatertightRays(const Ray& r)
      : WatertightRays(Vec3x8(r.org), Vec3x8(r.dir), float8(r.tnear)) {}
};

/// A triangle's factors of the bound, from its edge bound X (edge_bound8): 116u X, 56u X^2 and
/// 2^-12 X^2 (kThin). Computed once per triangle where many rays meet it.
struct EdgeFactors {
  float8 xm, xx, x_thin;
  EdgeFactors() = default;
  /// Lane k of `f` in every lane.
  RP_SIMD_INLINE EdgeFactors(const EdgeFactors& f, int k)
      : xm(simd::broadcast_lane(f.xm, k)),
        xx(simd::broadcast_lane(f.xx, k)),
        x_thin(simd::broadcast_lane(f.x_thin, k)) {}
  /// From the factors themselves.
  RP_SIMD_INLINE EdgeFactors(const float8& xm_, const float8& xx_, const float8& x_thin_)
      : xm(xm_), xx(xx_), x_thin(x_thin_) {}
  RP_SIMD_INLINE explicit EdgeFactors(const float8& x)
      : xm(x * float8(116.0f * 0x1p-24f)), xx(x * x * float8(56.0f * 0x1p-24f)), x_thin(x * x * float8(kThin)) {}
};

/// The bound per unit of D, h = 116u X M + 56u X^2 for M >= |c|, so that B = D h.
RP_SIMD_INLINE float8 bound_h(const float8& mc, const EdgeFactors& f) { return xsimd::fma(mc, f.xm, f.xx); }

/// Möller–Trumbore's third edge value, W = |den| - (U + V) (signed by den as U and V are).
RP_SIMD_INLINE float8 third_edge(const MtTerms& m) { return m.abs_den - (m.u + m.v); }

/// Möller–Trumbore's answer from its terms `m`, with the watertight rule for the bound `b` on
/// its values' errors (B) and rays of max-norms `d` (WatertightRays): the answer in `hit` (the
/// bits of moller_trumbore8 on every lane the rule leaves certain), and as the result the
/// lanes whose edge decisions the bound leaves uncertain, and the lanes nearly in the
/// triangle's plane inside its edges (see the top of this file).
RP_SIMD_INLINE uint32_t watertight_answer(const MtTerms& m, const float8& b, const float8& thin_below,
                                          const float8& tnear, const float8& tfar, TriHit8& hit) {
  const float8 w = third_edge(m);
  const float8 lowest = xsimd::min(m.u, xsimd::min(m.v, w));
  const float8 highest = xsimd::max(m.u, xsimd::max(m.v, w));
  // Inside Möller–Trumbore's edges: U, V >= 0 and U + V <= |den| (the sign of |den| - (U + V)
  // is exact), as mt_edges decides it but for den != 0, which mt_answer's t test implies. A
  // NaN lane (past a leaf's end; no other lane can have one) is outside (MINPS returns its
  // second operand on a NaN, and all three are NaN there).
  const mask8 inside = lowest >= float8(0.0f);
  hit = mt_answer(m, inside, tnear, tfar);
  // Sure of the edges: every value above B, or one below -B and another above B; that is
  // min(highest, |lowest|) > B (B > 0: the lowest value's sign is sure and the highest is
  // above B, so either all three are or two have opposite signs; no rounding: abs, min and max
  // are exact). A NaN lane compares false: certain, Möller–Trumbore's miss.
  const float8 reach = xsimd::min(highest, xsimd::abs(lowest));
  // A lane inside the edges nearly in the triangle's plane or on a needle (|den| < 2^-12 X^2 D,
  // or below a `thin_below` at least that) is decided exactly too, whatever its t: see the top of this
  // file.
  const mask8 thin = inside & (m.abs_den < thin_below);
  return simd::movemask((reach <= b) | thin);
}

/// Möller–Trumbore on rays (org, dir, tnear) of max-norms `d` (WatertightRays) and triangles
/// v0, e1 = v0 - v1, e2 = v2 - v0, Ng = e2 x e1 (cross_fma) with edge factors `f`: its answer
/// in `hit` (the bits of moller_trumbore8); returns the lanes it leaves to the exact decision
/// (watertight_answer), M taken lane by lane.
RP_SIMD_INLINE uint32_t watertight_mt8(const Vec3x8& org, const Vec3x8& dir, const float8& tnear, const float8& d,
                                       const float8& tfar, const Vec3x8& v0, const Vec3x8& e1, const Vec3x8& e2,
                                       const Vec3x8& ng, const EdgeFactors& f, TriHit8& hit) {
  const MtTerms m = mt_terms(org, dir, v0, e1, e2, ng);
  return watertight_answer(m, d * bound_h(max_abs(m.c), f), f.x_thin * d, tnear, tfar, hit);
}

/// The same for rays from one point (SharedOrigin), with the bound B = D h + g that it
/// gives, and the lanes whose |den| lies below `thin` (at least 2^-12 X^2 D) decided exactly as thin.
RP_SIMD_INLINE uint32_t watertight_mt8(const Vec3x8& org, const Vec3x8& dir, const float8& tnear, const float8& d,
                                       const float8& tfar, const Vec3x8& v0, const Vec3x8& e1, const Vec3x8& e2,
                                       const Vec3x8& ng, const float8& h, const float8& g, const float8& thin,
                                       TriHit8& hit) {
  const MtTerms m = mt_terms(org, dir, v0, e1, e2, ng);
  return watertight_answer(m, xsimd::fma(d, h, g), thin, tnear, tfar, hit);
}

/// The same for one ray broadcast (WatertightRays).
RP_SIMD_INLINE uint32_t watertight_mt8(const WatertightRays& r, const float8& tfar, const Vec3x8& v0, const Vec3x8& e1,
                                       const Vec3x8& e2, const Vec3x8& ng, const EdgeFactors& f, TriHit8& hit) {
  return watertight_mt8(r.org, r.dir, r.tnear, r.d, tfar, v0, e1, e2, ng, f, hit);
}

/// What the bound for rays from one point needs of a beam (PacketBeam), worked out once per
/// beam: whether its rays start at one point, that point (unmirrored; a -0 and a +0 coordinate
/// count as one: they give the same |c|), and the box of the rays' directions, unmirrored:
/// each component d_a lies within dmid_a +- drad_a, and |d_a| <= dmax. A ray's inverse is
/// 1 / |d_a| rounded once, so |d_a| lies within [1 / imax_a, 1 / imin_a] widened by a relative
/// 2^-22 (which also covers the rounding of these quotients, six in one division); drad's
/// extra 2^-21 of the largest |d_a| covers the rounding of dmid and drad.
struct OnePoint {
  bool valid = false;
  Vec3f origin;
  float dmid[3], drad[3], dmax;
  OnePoint() = default;
  explicit OnePoint(const PacketBeam& beam) {
    if (!beam.valid) return;
    for (int a = 0; a < 3; ++a) {
      const float lo = beam.omin[a].get(0);
      if (lo != beam.omax[a].get(0)) return;
      origin[a] = beam.neg[a] ? -lo : lo;
    }
    alignas(32) float inv[8] = {beam.imax[0].get(0),
                                beam.imax[1].get(0),
                                beam.imax[2].get(0),
                                beam.imin[0].get(0),
                                beam.imin[1].get(0),
                                beam.imin[2].get(0),
                                1.0f,
                                1.0f};
    (float8(1.0f) / float8::load_aligned(inv)).store_aligned(inv);
    dmax = 0.0f;
    for (int a = 0; a < 3; ++a) {
      const float low = inv[a] * (1.0f - 0x1p-22f), high = inv[3 + a] * (1.0f + 0x1p-22f);
      dmid[a] = beam.neg[a] ? -0.5f * (low + high) : 0.5f * (low + high);
      drad[a] = (0.5f * (high - low) + high * 0x1p-21f) * (1.0f + 0x1p-22f);
      dmax = std::max(dmax, high);
    }
    valid = true;
  }
};

/// The bound's factors for the triangles of a leaf (lanes) and the rays of a beam that all
/// start at one point o, as a pinhole camera's primary rays do. c = v0 - o is then the same
/// floats for every ray, and so is M, computed here once for all of them (the same bits as
/// each ray's own). R = |c x d| differs from ray to ray, but the beam holds every direction in
/// a box d = dmid + delta, |delta_a| <= drad_a, so each component of c x d lies within
/// |c x dmid| + |c_b| drad_a + |c_a| drad_b (a, b its two other axes), and the largest of the
/// three, widened for its own roundings and for R's (6.5u M D), bounds every ray's R: rho. So
/// the tighter bound u X (36 R + 41 M D + 54 X D) is at most B = D h + g, with
/// h = 41u X M + 54u X^2 and g = 36u X rho per triangle: one FMA a test, no R per lane. On a
/// group of camera rays rho is a few hundredths of M D and B is within a few percent of each
/// ray's own tighter bound. `shared` when the beam's rays start at one point (OnePoint::valid).
struct SharedOrigin {
  float8 h, g;  ///< 41u X M + 54u X^2 and 36u X rho per triangle, when `shared`
  float8 thin;  ///< 2^-12 X^2 times the beam's largest |d_a| (>= each ray's 2^-12 X^2 D)
  bool shared = false;
  RP_SIMD_INLINE SharedOrigin(const Vec3x8& v0, const EdgeFactors& f, const OnePoint& beam) {
    if (!beam.valid) return;
    const Vec3x8 c = v0 - Vec3x8(beam.origin);
    const float8 mc = max_abs(c);
    const float8 ax = xsimd::abs(c.x), ay = xsimd::abs(c.y), az = xsimd::abs(c.z);
    const float8 mx(beam.dmid[0]), my(beam.dmid[1]), mz(beam.dmid[2]);
    const float8 rx(beam.drad[0]), ry(beam.drad[1]), rz(beam.drad[2]);
    const float8 bx = xsimd::abs(xsimd::fms(c.y, mz, c.z * my)) + xsimd::fma(ay, rz, az * ry);
    const float8 by = xsimd::abs(xsimd::fms(c.z, mx, c.x * mz)) + xsimd::fma(az, rx, ax * rz);
    const float8 bz = xsimd::abs(xsimd::fms(c.x, my, c.y * mx)) + xsimd::fma(ax, ry, ay * rx);
    // The evaluation errs by under 12u M dmax and R by 6.5u M D: 2^-18 M dmax covers both.
    const float8 rho =
        xsimd::fma(xsimd::max(bx, xsimd::max(by, bz)), float8(1.0f + 0x1p-20f), mc * float8(beam.dmax * 0x1p-18f));
    h = xsimd::fma(mc, f.xm * float8(41.0f / 116.0f), f.xx * float8(54.0f / 56.0f));
    g = f.xm * float8(36.0f / 116.0f) * rho;
    thin = f.x_thin * float8(beam.dmax);
    shared = true;
  }
};

/// A test's terms again, for the lanes it left uncertain: the cold exact decisions below recompute
/// them from the leaf and the rays by the same operations on the same floats (so with the bits
/// of the fast path) rather than have the traversal hand its vectors over. Holds, per lane,
/// Möller–Trumbore's answer, its edge values U, V, W (signed by den), B, den's sign and whether
/// |den| < 2^-12 X^2 D.
struct Uncertain {
  alignas(32) float u[8], v[8], w[8], b[8], sign[8], t[8], bu[8], bv[8];
  uint32_t tiny = 0;
  uint32_t hits = 0;  ///< the lanes of Möller–Trumbore's answer that hit
  RP_SIMD_INLINE Uncertain(const Vec3x8& org, const Vec3x8& dir, const float8& tnear, const float8& d,
                           const float8& tfar, const Vec3x8& v0, const Vec3x8& e1, const Vec3x8& e2, const Vec3x8& ng,
                           const EdgeFactors& f) {
    const MtTerms m = mt_terms(org, dir, v0, e1, e2, ng);
    const float8 bound = d * bound_h(max_abs(m.c), f);
    TriHit8 mt;
    (void)watertight_answer(m, bound, f.x_thin * d, tnear, tfar, mt);  // Möller–Trumbore's answer, as the fast path's
    m.u.store_aligned(u);
    m.v.store_aligned(v);
    third_edge(m).store_aligned(w);
    bound.store_aligned(b);
    m.sign.store_aligned(sign);
    mt.t.store_aligned(t);
    mt.u.store_aligned(bu);
    mt.v.store_aligned(bv);
    tiny = simd::movemask(m.abs_den < f.x_thin * d);
    hits = simd::movemask(mt.hit);
  }

  /// Lane l's answer for the ray `r` and the triangle v0, v1, v2: the exact signs of its
  /// edges, each taken from Möller–Trumbore's value where that lies farther than B from 0 and
  /// from rp::edge_side otherwise; inside them, Möller–Trumbore's t (tested against tnear and
  /// tfar) and u, v (clamped to the triangle), but for a lane with |den| < 2^-12 X^2 D, which
  /// takes all of rp::intersect_triangle_exact (t in double). A ray and a triangle give these
  /// terms on every path (a packet, a ray alone, rays from one point), so a lane's answer does
  /// not depend on which path met it, nor on whether that path's bound was certain of it.
  Intersection<float> lane(int l, const Ray& r, const Vec3f& v0, const Vec3f& v1, const Vec3f& v2) const {
    if (tiny >> l & 1u) return intersect_triangle_exact(r, v0, v1, v2);
    // The exact edge functions of (v2, v0), (v0, v1) and (v1, v2) are U, V, W times den's sign.
    const int s = std::signbit(sign[l]) ? -1 : 1;
    const auto side = [&](float value, const Vec3f& p, const Vec3f& q) {
      if (value > b[l]) return 1;
      if (value < -b[l]) return -1;
      return s * edge_side(p, q, r.org, r.dir);
    };
    const int su = side(u[l], v2, v0), sv = side(v[l], v0, v1), sw = side(w[l], v1, v2);
    if (!inside_edges(su, sv, sw) || !in_ray_interval(r, t[l])) return {};
    const float cu = std::clamp(bu[l], 0.0f, 1.0f);
    return make_intersection(t[l], cu, std::clamp(bv[l], 0.0f, 1.0f - cu));
  }
};

/// A test's answer with the lanes it left uncertain decided exactly: an out-parameter of the
/// cold exact decisions, which make every lane's answer (where the test was certain,
/// Möller–Trumbore's from Uncertain: the fast path's bits). So nothing of the fast path's
/// answer need be kept across their call, and the caller's answer stays in registers (passed
/// to them by reference, it would live in memory through the traversal, and the watertight
/// variant measured slower).
struct ExactAnswers {
  TriHit8 w;
  /// Lane l, for each lane l of `unsure`, answer(l) (an Intersection<float>); `un`'s
  /// Möller–Trumbore answer in the others.
  template <class Answer>
  void fill(const Uncertain& un, uint32_t unsure, Answer&& answer) {
    simd::Spill<3> s(float8::load_aligned(un.t), float8::load_aligned(un.bu), float8::load_aligned(un.bv));
    uint32_t bits = un.hits & ~unsure;
    for (uint32_t b = unsure; b; b &= b - 1) {
      const int l = std::countr_zero(b);
      const Intersection<float> x = answer(l);
      s.lanes[0][l] = x.t;
      s.lanes[1][l] = x.u;
      s.lanes[2][l] = x.v;
      bits |= uint32_t(x.hit) << l;
    }
    w = {simd::mask_from_bits(bits), s.load(0), s.load(1), s.load(2)};
  }
};

/// The answers of one ray (with `tfar`) against the triangles of `leaf`, the lanes `unsure`
/// decided exactly (the leaf's edges, normals and factors made again as WatertightKernel::Block makes
/// them). Out of line and cold: inlined, it would make the traversal around the kernel keep
/// its vectors in memory (diffuse rays measured much slower, though it runs for a small fraction
/// of leaf tests; figures: docs/notes/2026-11-29-figures-from-code-comments.md).
[[gnu::noinline, gnu::cold]] inline void exact_single(const Leaf& leaf, const Ray& ray, float tfar, uint32_t unsure,
                                                      ExactAnswers& out) {
  const LeafView lv(leaf);
  const Vec3x8 e1 = lv.e1(), e2 = lv.e2();
  const WatertightRays cr(ray);
  const Uncertain un(cr.org, cr.dir, cr.tnear, cr.d, float8(tfar), lv.v0, e1, e2, simd::cross_fma(e2, e1),
                     EdgeFactors(edge_bound8(e1, e2)));
  Ray r = ray;
  r.tfar = tfar;
  out.fill(un, unsure, [&](int l) {
    const auto k = uint32_t(l);
    return un.lane(l, r, leaf.vertex(k, 0), leaf.vertex(k, 1), leaf.vertex(k, 2));
  });
}

/// The same for the rays of a packet (SoA, as loaded) against triangle k of `leaf`, the lanes
/// `unsure` decided exactly (made again as WatertightKernel::Triangle makes it: lane k of the leaf's).
[[gnu::noinline, gnu::cold]] inline void exact_packet(const RayPacket& p, const float8& tfar, const Leaf& leaf,
                                                      uint32_t k, uint32_t unsure, ExactAnswers& out) {
  const LeafView lv(leaf);
  const Vec3x8 e1 = lv.e1(), e2 = lv.e2(), ng = simd::cross_fma(e2, e1);
  const int i = int(k);
  const Uncertain un(p.org, p.dir, p.tnear, max_abs(p.dir), tfar, lv.v0.broadcast(i), e1.broadcast(i), e2.broadcast(i),
                     ng.broadcast(i), EdgeFactors(EdgeFactors(edge_bound8(e1, e2)), i));
  const Vec3f v0 = leaf.vertex(k, 0), v1 = leaf.vertex(k, 1), v2 = leaf.vertex(k, 2);
  simd::Spill<8> rays(p.org.x, p.org.y, p.org.z, p.dir.x, p.dir.y, p.dir.z, p.tnear, tfar);
  const auto& q = rays.lanes;
  out.fill(un, unsure, [&](int l) {
    const Ray r{{q[0][l], q[1][l], q[2][l]}, q[6][l], {q[3][l], q[4][l], q[5][l]}, q[7][l]};
    return un.lane(l, r, v0, v1, v2);
  });
}

/// The triangle test of the watertight variant as it runs: Möller–Trumbore with a bound on
/// the error of each edge decision, decided exactly (rp::edge_side) for the lanes the bound
/// leaves uncertain (watertight.h: why every lane's edge decisions are exact).
struct WatertightKernel {
  /// MtKernel's Block, with the triangles' factors of the bound and the leaf for the exact decision.
  struct Block : MtKernel::Block {
    EdgeFactors f;      ///< the triangles' factors of the bound (edge_bound8)
    const float* leaf;  ///< the leaf's words, where the exact decision reads the corners (LeafView::words)
    RP_SIMD_INLINE explicit Block(const LeafView& lv) : MtKernel::Block(lv), f(edge_bound8(e1, e2)), leaf(lv.words) {}
  };
  /// A beam's rays as the bound for rays from one point takes them (once per beam), and a
  /// leaf's triangles against them (SharedOrigin).
  using Beam = OnePoint;
  struct Origins : SharedOrigin {
    RP_SIMD_INLINE Origins(const Block& b, const Beam& beam) : SharedOrigin(b.v0, b.f, beam) {}
  };
  struct Single {
    WatertightRays r;
    const Ray* ray;  ///< for the exact decision (a pointer: the ray is copied nowhere on the fast path)
    RP_SIMD_INLINE explicit Single(const Ray& ray_) : r(ray_), ray(&ray_) {}
    Single(const RayPacket& p, int lane, const Ray& ray_)
        : r(p.org.broadcast(lane), p.dir.broadcast(lane), simd::broadcast_lane(p.tnear, lane)), ray(&ray_) {}
    RP_SIMD_INLINE TriHit8 block(const Block& b, const float8& tfar) const {
      TriHit8 h;
      decide_exactly(b, tfar, watertight_mt8(r, tfar, b.v0, b.e1, b.e2, b.ng, b.f, h), h);
      return h;
    }
    /// The same for a ray of the beam `og` was made for, with its bound where the beam's rays
    /// start at one point (the same answers).
    RP_SIMD_INLINE TriHit8 block(const Block& b, const float8& tfar, const Origins& og) const {
      if (!og.shared) return block(b, tfar);
      TriHit8 h;
      decide_exactly(
          b, tfar, watertight_mt8(r.org, r.dir, r.tnear, r.d, tfar, b.v0, b.e1, b.e2, b.ng, og.h, og.g, og.thin, h), h);
      return h;
    }

   private:
    /// `h` replaced by the answer with the lanes `unsure` decided exactly, if there are any.
    RP_SIMD_INLINE void decide_exactly(const Block& b, const float8& tfar, uint32_t unsure, TriHit8& h) const {
      if (unsure) [[unlikely]] {
        ExactAnswers s;
        exact_single(Leaf(b.leaf), *ray, tfar.get(0), unsure, s);
        h = s.w;
      }
    }
  };
  /// MtKernel's Triangle, with the factors of its bound in a, b and thin, and where the exact decision
  /// reads it. For rays each with their own M: the edge factors xm, xx and x_thin (B =
  /// D (M xm + xx), lanes with |den| < x_thin D thin); for rays from one point (SharedOrigin,
  /// `shared`): its h, g and thin (B = D h + g, lanes with |den| < thin thin).
  struct Triangle : MtKernel::Triangle {
    float8 a, b, thin;
    const float* leaf = nullptr;  ///< the leaf's words, where the exact decision reads the corners
    uint32_t k = 0;
    bool shared = false;
    Triangle() = default;
    /// Triangle k of a leaf's Block, in every lane, each ray with its own M.
    RP_SIMD_INLINE Triangle(const Block& bl, uint32_t k_)
        : MtKernel::Triangle(bl, k_),
          a(simd::broadcast_lane(bl.f.xm, int(k_))),
          b(simd::broadcast_lane(bl.f.xx, int(k_))),
          thin(simd::broadcast_lane(bl.f.x_thin, int(k_))),
          leaf(bl.leaf),
          k(k_) {}
    /// The same, with SharedOrigin's factors when the rays start at one point.
    RP_SIMD_INLINE Triangle(const Block& bl, uint32_t k_, const SharedOrigin& o)
        : MtKernel::Triangle(bl, k_), leaf(bl.leaf), k(k_), shared(o.shared) {
      const int i = int(k_);
      a = simd::broadcast_lane(shared ? o.h : bl.f.xm, i);
      b = simd::broadcast_lane(shared ? o.g : bl.f.xx, i);
      thin = simd::broadcast_lane(shared ? o.thin : bl.f.x_thin, i);
    }
  };
  struct Packet {
    const RayPacket* p = nullptr;
    float8 d;  ///< the rays' max-norms D, their factor in the bound (WatertightRays)
    Packet() = default;
    Packet(const RayPacket& packet, std::span<const Ray>) : p(&packet), d(max_abs(packet.dir)) {}
    /// The answers of the lanes `lanes` (the caller ignores the others, which therefore never
    /// go to the exact decision).
    RP_SIMD_INLINE TriHit8 test(const Triangle& t, const float8& tfar, uint32_t lanes) const {
      TriHit8 h;
      const uint32_t unsure =
          (t.shared ? watertight_mt8(p->org, p->dir, p->tnear, d, tfar, t.v0, t.e1, t.e2, t.ng, t.a, t.b, t.thin, h)
                    : watertight_mt8(p->org, p->dir, p->tnear, d, tfar, t.v0, t.e1, t.e2, t.ng,
                                     EdgeFactors(t.a, t.b, t.thin), h)) &
          lanes;
      if (unsure) [[unlikely]] {
        ExactAnswers s;
        exact_packet(*p, tfar, Leaf(t.leaf), t.k, unsure, s);
        h = s.w;
      }
      return h;
    }
  };
};

}  // namespace rp::bvh8
