#pragma once
/// The slab tests of the simd backend (the lecture notes' slab method, 8 wide): one ray against
/// a node's 8 child boxes (SingleRay, intersect_node; the stream's SlabRay, SlabRays8), 8 rays
/// against one box (RayPacket, intersect_box), a beam of rays against 8 boxes (PacketBeam,
/// PacketBeams8) and the near-first order of a node's children for a packet or a group.
/// AVX2+FMA translation units only.

#include <limits>

#include "backends/simd/bvh8.h"
#include "simd/float8.h"

namespace rp::bvh8 {

using simd::float8;
using simd::mask8;
using simd::Vec3x8;

/// Widening of a box's exit distance that makes float slab tests conservative: Ize, "Robust
/// BVH Ray Traversal", JCGT 2(2), 2013, multiplies t_far by 1 + 2 gamma(3) (gamma(n) =
/// n eps / (1 - n eps), eps = 2^-24).
inline constexpr float kSlabPad = 1.0f + 2.0f * (3.0f * 0x1p-24f) / (1.0f - 3.0f * 0x1p-24f);

/// A ray's slab-test figures as scalars: what SingleRay broadcasts, and what the ray-stream
/// traversal (stream.h) keeps for each ray of a batch.
struct SlabRay {
  float inv[3];  ///< 1 / dir (1/±0 = ±inf)
  float oi[3];   ///< org * inv, for the one-FMA slab distances
  float pad;     ///< the slack intersect_node grants an exit distance (0 when exact)
  /// Offset (in floats, from Bvh8Node::lo_x) of the node array holding each axis's near
  /// plane, from the ray's octant; the far plane's is 24, 40 or 56 minus it.
  int near[3];
  /// The one-FMA form could meet a NaN: a direction component is +-0, or so small (below
  /// 2^-128) that its inverse, or org * inv, overflows to inf. Such a ray takes the exact form.
  bool exact;

  SlabRay() = default;
  explicit SlabRay(const Ray& r) {
    // fms(p, inv, oi) rounds org * inv once (error <= |org * inv| 2^-24) and the result once
    // (covered by kSlabPad); the exit distance is widened by twice the first bound.
    float m = 0.0f;
    exact = false;
    for (int a = 0; a < 3; ++a) {
      inv[a] = 1.0f / r.dir[a];
      oi[a] = r.org[a] * inv[a];
      exact = exact || !std::isfinite(inv[a]) || !std::isfinite(oi[a]);
      if (r.dir[a] != 0.0f) m = std::max(m, std::abs(r.org[a] / r.dir[a]));
      near[a] = std::signbit(r.dir[a]) ? 24 + 8 * a : 8 * a;  // hi row or lo row of the axis
    }
    pad = exact ? 0.0f : m * 0x1p-23f;
  }
};

/// SlabRay of 8 rays at once, from their origins and directions in SoA, with the same bits
/// lane by lane: the same IEEE quotients and products, the same finiteness test, and the
/// same largest |org / dir| (among finite, non-negative values, where max has one answer).
/// What the ray-stream traversal's entry loop takes instead of eight scalar SlabRays (six
/// divisions each). Lanes of invalid rays hold values never to be read.
struct SlabRays8 {
  simd::Spill<7> rows;   ///< inv x, y, z, oi x, y, z, pad
  uint32_t exact = 0;    ///< lanes whose SlabRay::exact is set
  uint32_t negative[3];  ///< per axis, the lanes whose direction has its sign bit set

  SlabRays8(const Vec3x8& org, const Vec3x8& dir) {
    const float8 one(1.0f), zero(0.0f), huge(std::numeric_limits<float>::max());
    const float8 d[3] = {dir.x, dir.y, dir.z}, o[3] = {org.x, org.y, org.z};
    float8 inv[3], oi[3], m = zero;
    mask8 exact_lanes(false);
    for (int a = 0; a < 3; ++a) {
      inv[a] = one / d[a];
      oi[a] = o[a] * inv[a];
      exact_lanes = exact_lanes | !(xsimd::abs(inv[a]) <= huge) | !(xsimd::abs(oi[a]) <= huge);
      m = xsimd::max(m, xsimd::select(d[a] != zero, xsimd::abs(o[a] / d[a]), zero));
      negative[a] = simd::movemask(simd::sign_mask(d[a]));
    }
    const float8 pad = xsimd::select(exact_lanes, zero, m * float8(0x1p-23f));
    rows = simd::Spill<7>(inv[0], inv[1], inv[2], oi[0], oi[1], oi[2], pad);
    exact = simd::movemask(exact_lanes);
  }

  /// Lane l as SlabRay(ray l).
  SlabRay lane(int l) const {
    SlabRay s;
    for (int a = 0; a < 3; ++a) {
      s.inv[a] = rows.lanes[a][l];
      s.oi[a] = rows.lanes[3 + a][l];
      s.near[a] = (negative[a] >> l & 1u) ? 24 + 8 * a : 8 * a;
    }
    s.pad = rows.lanes[6][l];
    s.exact = exact >> l & 1u;
    return s;
  }
};

/// One ray prepared for the single-ray traversal: SlabRay's figures broadcast, and the near
/// and far planes of each axis chosen once from the ray's octant (madmann91/bvh, tinybvh).
/// The octant follows the sign bit, so -0 counts as negative and its inverse -inf pairs with
/// the right plane.
struct SingleRay {
  float8 org_x, org_y, org_z, inv_x, inv_y, inv_z;
  float8 oi_x, oi_y, oi_z;  ///< org * inv, for the one-FMA slab distances
  float8 abs_pad;           ///< bound on the rounding error of org * inv (see intersect_node)
  float pad;                ///< SlabRay::pad
  bool exact_slabs;         ///< SlabRay::exact
  int near_x, near_y, near_z, far_x, far_y, far_z;

  explicit SingleRay(const Ray& r) : SingleRay(r, SlabRay(r)) {}
  /// From figures already worked out (by SlabRay(r)): no division.
  SingleRay(const Ray& r, const SlabRay& s)
      : org_x(r.org.x),
        org_y(r.org.y),
        org_z(r.org.z),
        inv_x(s.inv[0]),
        inv_y(s.inv[1]),
        inv_z(s.inv[2]),
        oi_x(s.oi[0]),
        oi_y(s.oi[1]),
        oi_z(s.oi[2]),
        abs_pad(s.pad),
        pad(s.pad),
        exact_slabs(s.exact),
        near_x(s.near[0]),
        near_y(s.near[1]),
        near_z(s.near[2]),
        far_x(24 - s.near[0]),
        far_y(40 - s.near[1]),
        far_z(56 - s.near[2]) {}
};

/// The decision of intersect_node's one-FMA form from the slab distances of the near (tn) and
/// far (tf) planes: the children entered no later than they are left, within [tnear, tfar],
/// the exits widened by kSlabPad and the slack (`slack` in every lane, `pad` as a scalar),
/// and the entry distances (>= +0). No NaN arises in this form (finite inv and org * inv; an
/// empty child's planes give +-inf) and tnear + 0 is >= +0 (a -0 tnear becomes +0), so the
/// entry's max is exact in integer order, and the padded exits' min is exact where they are
/// >= +0 and negative, a miss either way, where they are not (simd::max_bits): one cycle a
/// step where float max and min take four (diffuse single rays measured closer to Embree's
/// rtcIntersect1; figures: docs/notes/2026-11-29-figures-from-code-comments.md).
RP_SIMD_INLINE uint32_t slab_hits(const float8& tn_x, const float8& tn_y, const float8& tn_z, const float8& tf_x,
                                  const float8& tf_y, const float8& tf_z, float tnear, float tfar, const float8& slack,
                                  float pad, float8& t_enter) {
  const float8 p(kSlabPad);
  t_enter = simd::max_bits(simd::max_bits(tn_x, tn_y), simd::max_bits(tn_z, float8(tnear + 0.0f)));
  const float8 t_exit =
      simd::min_bits(simd::min_bits(xsimd::fma(tf_x, p, slack), xsimd::fma(tf_y, p, slack)),
                     simd::min_bits(xsimd::fma(tf_z, p, slack), float8(std::fma(tfar, kSlabPad, pad))));
  return ~simd::greater_bits(t_enter, t_exit) & 0xffu;
}

/// Slab test ×8: one ray against the 8 child boxes of `n` (the lecture notes' slab method; the swap is
/// the octant's near/far choice). Returns the bit mask of children hit within [tnear, tfar]
/// and their entry distances. An entry distance may exceed the true one by the same slack
/// the exit is granted, so a caller that later compares it with a hit distance must compare
/// with fma(t_hit, kSlabPad, r.pad) (see traverse_closest).
///
/// Common case: each slab distance is one FMA, plane * inv - org * inv (as Embree's fast
/// traversal); the exit distance is widened by kSlabPad for the final rounding and by
/// abs_pad for the rounding of org * inv, so the test stays conservative. A ray with
/// SingleRay::exact_slabs (a +-0 direction component, or one whose inverse overflows) takes
/// the exact form (plane - org) * inv instead: its 0 * inf slab (origin on a face plane,
/// parallel to it) is NaN and drops out of the max/min chains, so it imposes no constraint,
/// as a closed box should. Empty children (lo = +inf, hi = -inf) never hit.
RP_SIMD_INLINE uint32_t intersect_node(const Bvh8Node& n, const SingleRay& r, float tnear, float tfar,
                                       float8& t_enter) {
  using simd::max_b_on_nan;
  using simd::min_b_on_nan;
  const float* base = n.lo_x;
  if (!r.exact_slabs) {
    const float8 tn_x = xsimd::fms(float8::load_aligned(base + r.near_x), r.inv_x, r.oi_x);
    const float8 tn_y = xsimd::fms(float8::load_aligned(base + r.near_y), r.inv_y, r.oi_y);
    const float8 tn_z = xsimd::fms(float8::load_aligned(base + r.near_z), r.inv_z, r.oi_z);
    const float8 tf_x = xsimd::fms(float8::load_aligned(base + r.far_x), r.inv_x, r.oi_x);
    const float8 tf_y = xsimd::fms(float8::load_aligned(base + r.far_y), r.inv_y, r.oi_y);
    const float8 tf_z = xsimd::fms(float8::load_aligned(base + r.far_z), r.inv_z, r.oi_z);
    return slab_hits(tn_x, tn_y, tn_z, tf_x, tf_y, tf_z, tnear, tfar, r.abs_pad, r.pad, t_enter);
  }
  const float8 tn_x = (float8::load_aligned(base + r.near_x) - r.org_x) * r.inv_x;
  const float8 tn_y = (float8::load_aligned(base + r.near_y) - r.org_y) * r.inv_y;
  const float8 tn_z = (float8::load_aligned(base + r.near_z) - r.org_z) * r.inv_z;
  const float8 tf_x = (float8::load_aligned(base + r.far_x) - r.org_x) * r.inv_x;
  const float8 tf_y = (float8::load_aligned(base + r.far_y) - r.org_y) * r.inv_y;
  const float8 tf_z = (float8::load_aligned(base + r.far_z) - r.org_z) * r.inv_z;
  t_enter = max_b_on_nan(tn_z, max_b_on_nan(tn_y, max_b_on_nan(tn_x, float8(tnear + 0.0f))));
  const float8 t_exit = min_b_on_nan(tf_z, min_b_on_nan(tf_y, min_b_on_nan(tf_x, float8(tfar))));
  return simd::movemask(t_enter <= t_exit * float8(kSlabPad));
}

/// Eight rays in SoA prepared for the packet traversal.
struct RayPacket {
  Vec3x8 org, dir, inv;
  mask8 neg_x, neg_y, neg_z;  ///< sign bit of each direction component
  float8 tnear;
  Vec3x8 oi;       ///< org * inv, for the one-FMA slab form of intersect_box_octant
  float8 abs_pad;  ///< bound on the rounding error of org * inv, per lane
};

/// Slab test ×8 across rays: the 8 rays of `p` against box [lo, hi], each ray with its own
/// tfar. Near and far planes per lane from the direction's sign bit; NaN handling as
/// intersect_node. Returns the lanes that hit.
inline uint32_t intersect_box(const RayPacket& p, const Vec3f& lo, const Vec3f& hi, const float8& tfar) {
  using simd::max_b_on_nan;
  using simd::min_b_on_nan;
  const float8 lx(lo.x), ly(lo.y), lz(lo.z), hx(hi.x), hy(hi.y), hz(hi.z);
  const float8 tn_x = (xsimd::select(p.neg_x, hx, lx) - p.org.x) * p.inv.x;
  const float8 tn_y = (xsimd::select(p.neg_y, hy, ly) - p.org.y) * p.inv.y;
  const float8 tn_z = (xsimd::select(p.neg_z, hz, lz) - p.org.z) * p.inv.z;
  const float8 tf_x = (xsimd::select(p.neg_x, lx, hx) - p.org.x) * p.inv.x;
  const float8 tf_y = (xsimd::select(p.neg_y, ly, hy) - p.org.y) * p.inv.y;
  const float8 tf_z = (xsimd::select(p.neg_z, lz, hz) - p.org.z) * p.inv.z;
  const float8 t_enter = max_b_on_nan(tn_z, max_b_on_nan(tn_y, max_b_on_nan(tn_x, p.tnear)));
  const float8 t_exit = min_b_on_nan(tf_z, min_b_on_nan(tf_y, min_b_on_nan(tf_x, tfar)));
  return simd::movemask(t_enter <= t_exit * kSlabPad);
}

/// Interval-arithmetic bounds of a packet (the beam of its rays) for culling a node's 8
/// children at once before the per-ray slab tests (Wald, Boulos, Shirley, "Ray Tracing
/// Deformable Scenes using Dynamic Bounding Volume Hierarchies", ACM TOG 26(1), 2007, sec.
/// 4.2). Valid only when every active ray has the same nonzero direction sign per axis;
/// then each axis is mirrored so that directions are positive, and a child is culled when
/// the earliest possible entry over all rays exceeds the latest possible exit.
struct PacketBeam;

/// The bounds of a PacketBeam as scalars (52 bytes): mirrored origin and inverse-direction
/// ranges per axis and the least tnear. The large-packet traversal keeps them per packet
/// and merges them over ranges of packets.
struct BeamBounds {
  float omin[3], omax[3], imin[3], imax[3], tnear_min;

  /// The bounds of both: the beam holding the rays of each.
  static BeamBounds merge(const BeamBounds& a, const BeamBounds& b) {
    BeamBounds m;
    for (int k = 0; k < 3; ++k) {
      m.omin[k] = std::min(a.omin[k], b.omin[k]);
      m.omax[k] = std::max(a.omax[k], b.omax[k]);
      m.imin[k] = std::min(a.imin[k], b.imin[k]);
      m.imax[k] = std::max(a.imax[k], b.imax[k]);
    }
    m.tnear_min = std::min(a.tnear_min, b.tnear_min);
    return m;
  }
};

struct PacketBeam {
  bool valid = false;
  bool neg[3] = {};
  float8 omin[3], omax[3], imin[3], imax[3];  ///< mirrored origin and inverse-direction ranges
  float8 tnear_min;

  PacketBeam() = default;
  /// The beam of `b` for rays of direction signs `negative` (valid).
  PacketBeam(const BeamBounds& b, const bool negative[3]) : valid(true) {
    for (int a = 0; a < 3; ++a) {
      neg[a] = negative[a];
      omin[a] = float8(b.omin[a]);
      omax[a] = float8(b.omax[a]);
      imin[a] = float8(b.imin[a]);
      imax[a] = float8(b.imax[a]);
    }
    tnear_min = float8(b.tnear_min);
  }

  /// The scalar bounds of a valid beam.
  BeamBounds bounds() const {
    BeamBounds b;
    for (int a = 0; a < 3; ++a) {
      b.omin[a] = omin[a].get(0);
      b.omax[a] = omax[a].get(0);
      b.imin[a] = imin[a].get(0);
      b.imax[a] = imax[a].get(0);
    }
    b.tnear_min = tnear_min.get(0);
    return b;
  }

  PacketBeam(const RayPacket& p, uint32_t active) {
    if (!active) return;
    const mask8 on = simd::mask_from_bits(active);
    const float8 inf(std::numeric_limits<float>::infinity());
    const float8 org[3] = {p.org.x, p.org.y, p.org.z}, inv[3] = {p.inv.x, p.inv.y, p.inv.z};
    const mask8 negm[3] = {p.neg_x, p.neg_y, p.neg_z};
    for (int a = 0; a < 3; ++a) {
      const uint32_t n = simd::movemask(negm[a]) & active;
      if (n != 0 && n != active) return;  // mixed signs on this axis
      neg[a] = n != 0;
      const float8 o = neg[a] ? -org[a] : org[a], i = neg[a] ? -inv[a] : inv[a];
      const float lo_i = simd::reduce_min(xsimd::select(on, i, inf)),
                  hi_i = simd::reduce_max(xsimd::select(on, i, -inf));
      if (!(lo_i > 0.0f) || !(hi_i < std::numeric_limits<float>::infinity())) return;  // a zero direction
      omin[a] = float8(simd::reduce_min(xsimd::select(on, o, inf)));
      omax[a] = float8(simd::reduce_max(xsimd::select(on, o, -inf)));
      imin[a] = float8(lo_i);
      imax[a] = float8(hi_i);
    }
    tnear_min = float8(simd::reduce_min(xsimd::select(on, p.tnear, inf)));
    valid = true;
  }

  /// Children of `n` that some ray of the beam may hit before `tfar_max`; conservative (a
  /// relative slack of 2^-20 covers the rounding of the bounds).
  uint32_t cull(const Bvh8Node& n, float tfar_max) const {
    const float* lo[3] = {n.lo_x, n.lo_y, n.lo_z};
    const float* hi[3] = {n.hi_x, n.hi_y, n.hi_z};
    const float8 zero(0.0f);
    float8 enter = tnear_min, exit(tfar_max);
    for (int a = 0; a < 3; ++a) {
      const float8 l = float8::load_aligned(lo[a]), h = float8::load_aligned(hi[a]);
      const float8 near = neg[a] ? -h : l, far = neg[a] ? -l : h;
      const float8 dn = near - omax[a], df = far - omin[a];
      enter = xsimd::max(enter, dn * xsimd::select(dn >= zero, imin[a], imax[a]));
      exit = xsimd::min(exit, df * xsimd::select(df >= zero, imax[a], imin[a]));
    }
    const float8 slack = (xsimd::abs(enter) + xsimd::abs(exit)) * float8(0x1p-20f);
    return simd::movemask(enter - slack <= exit);
  }
};

/// The beams of 8 packets of one octant, one per lane (structure of arrays): the transposed
/// PacketBeam, for culling 8 packets against one box in one step.
struct PacketBeams8 {
  float8 omin[3], omax[3], imin[3], imax[3];  ///< mirrored origin and inverse-direction ranges
  float8 tnear_min, tfar_max;                 ///< a lane that no ray may use has tnear_min = +inf

  /// Lanes whose beam some ray may take into box [lo, hi] (of the octant `neg`) within its
  /// interval; conservative as PacketBeam::cull, with the same arithmetic.
  uint32_t cull(const bool neg[3], const Vec3f& lo, const Vec3f& hi) const {
    const float l[3] = {lo.x, lo.y, lo.z}, h[3] = {hi.x, hi.y, hi.z};
    const float8 zero(0.0f);
    float8 enter = tnear_min, exit = tfar_max;
    for (int a = 0; a < 3; ++a) {
      const float8 near(neg[a] ? -h[a] : l[a]), far(neg[a] ? -l[a] : h[a]);
      const float8 dn = near - omax[a], df = far - omin[a];
      enter = xsimd::max(enter, dn * xsimd::select(dn >= zero, imin[a], imax[a]));
      exit = xsimd::min(exit, df * xsimd::select(df >= zero, imax[a], imin[a]));
    }
    const float8 slack = (xsimd::abs(enter) + xsimd::abs(exit)) * float8(0x1p-20f);
    return simd::movemask(enter - slack <= exit);
  }
};

/// Slab test ×8 across rays for a packet whose rays share one octant and have no zero
/// direction component (PacketBeam::valid): near and far planes chosen once per packet, one
/// FMA per slab distance with the error bounds of intersect_node. Returns the lanes that hit.
inline uint32_t intersect_box_octant(const RayPacket& p, const bool neg[3], const Vec3f& lo, const Vec3f& hi,
                                     const float8& tfar) {
  using simd::max_b_on_nan;
  using simd::min_b_on_nan;
  const float8 tn_x = xsimd::fms(float8(neg[0] ? hi.x : lo.x), p.inv.x, p.oi.x);
  const float8 tn_y = xsimd::fms(float8(neg[1] ? hi.y : lo.y), p.inv.y, p.oi.y);
  const float8 tn_z = xsimd::fms(float8(neg[2] ? hi.z : lo.z), p.inv.z, p.oi.z);
  const float8 tf_x = xsimd::fms(float8(neg[0] ? lo.x : hi.x), p.inv.x, p.oi.x);
  const float8 tf_y = xsimd::fms(float8(neg[1] ? lo.y : hi.y), p.inv.y, p.oi.y);
  const float8 tf_z = xsimd::fms(float8(neg[2] ? lo.z : hi.z), p.inv.z, p.oi.z);
  const float8 t_enter = max_b_on_nan(tn_z, max_b_on_nan(tn_y, max_b_on_nan(tn_x, p.tnear)));
  const float8 t_exit = min_b_on_nan(tf_z, min_b_on_nan(tf_y, min_b_on_nan(tf_x, tfar)));
  return simd::movemask(t_enter <= xsimd::fma(t_exit, float8(kSlabPad), p.abs_pad));
}

/// The keys that order a node's children near-first along direction signs (sx, sy, sz): sum
/// over axes of sign * (lo + hi), one 8-wide op; the nearest child has the smallest key.
inline float8 near_first_keys(const Bvh8Node& n, const float8& sx, const float8& sy, const float8& sz) {
  return sx * (float8::load_aligned(n.lo_x) + float8::load_aligned(n.hi_x)) +
         sy * (float8::load_aligned(n.lo_y) + float8::load_aligned(n.hi_y)) +
         sz * (float8::load_aligned(n.lo_z) + float8::load_aligned(n.hi_z));
}

}  // namespace rp::bvh8
