#pragma once
/// Möller–Trumbore, 8 wide, in the form the simd backend's default variant runs it: one ray
/// against 8 triangles and 8 rays against one triangle by the same function
/// (moller_trumbore8), the terms the watertight test bounds (MtTerms, watertight.h), a leaf's
/// triangles read as 8-wide corners (LeafView), and MtKernel, the test as the traversal loops
/// call it. AVX2+FMA translation units only.

#include <span>

#include "backends/simd/slab.h"
#include "core/geometry/triangle.h"
#include "core/ray.h"

namespace rp::bvh8 {

/// Result of an 8-wide triangle test (moller_trumbore8, watertight.h): lanes that hit, with t and
/// the barycentrics (u, v).
struct TriHit8 {
  mask8 hit;
  float8 t, u, v;
};

/// The terms moller_trumbore8 decides on, which the watertight test (watertight.h) also bounds.
struct MtTerms {
  Vec3x8 c;        ///< v0 - org
  Vec3x8 r;        ///< c x dir
  float8 den;      ///< Ng . dir
  float8 sign;     ///< the sign bit of den, xored into U, V, T
  float8 abs_den;  ///< |den|
  float8 u, v;     ///< the unnormalised barycentrics, sign-corrected
  float8 tn;       ///< Ng . c, sign-corrected: t times |den|
};

RP_SIMD_INLINE MtTerms mt_terms(const Vec3x8& org, const Vec3x8& dir, const Vec3x8& v0, const Vec3x8& e1,
                                const Vec3x8& e2, const Vec3x8& ng) {
  MtTerms m;
  m.c = v0 - org;
  m.r = simd::cross_fma(m.c, dir);
  m.den = simd::dot_fma(ng, dir);
  m.sign = m.den & float8(-0.0f);
  m.abs_den = m.den ^ m.sign;
  m.u = simd::dot_fma(m.r, e2) ^ m.sign;
  m.v = simd::dot_fma(m.r, e1) ^ m.sign;
  m.tn = simd::dot_fma(ng, m.c) ^ m.sign;
  return m;
}

/// The lanes whose ray passes inside the triangle (or on its border) by moller_trumbore8's
/// edge tests.
RP_SIMD_INLINE mask8 mt_edges(const MtTerms& m) {
  const float8 zero(0.0f);
  return (m.den != zero) & (m.u >= zero) & (m.v >= zero) & (m.u + m.v <= m.abs_den);
}

/// moller_trumbore8's answer from its terms and the lanes inside its edges (mt_edges, or a mask
/// equal to it wherever den != 0: a lane with den = 0 has t = Tn / 0, infinite or NaN, which
/// the t test rejects).
RP_SIMD_INLINE TriHit8 mt_answer(const MtTerms& m, const mask8& edges, const float8& tnear, const float8& tfar) {
  const float8 inf(std::numeric_limits<float>::infinity());
  const float8 inv = float8(1.0f) / m.abs_den;
  const float8 t = m.tn * inv;
  const mask8 hit = edges & (t >= tnear) & (t <= tfar) & (t < inf);
  return {hit, t, m.u * inv, m.v * inv};
}

/// moller_trumbore8's answer from its terms.
RP_SIMD_INLINE TriHit8 mt_answer(const MtTerms& m, const float8& tnear, const float8& tfar) {
  return mt_answer(m, mt_edges(m), tnear, tfar);
}

/// Möller–Trumbore ×8 in the normal-first factoring of rp::intersect_triangle_mt_normal (Möller
/// and Trumbore 1997; Kensler and Shirley 2006; Embree's default triangle intersector), lane
/// by lane exactly as that scalar routine: the same FMAs in the same order, so each lane has
/// its bits. Edge tests compare the unnormalised U, V against |D.Ng| before any division, so
/// the decisions at shared edges are those of Embree's default intersector. Takes the
/// triangle as v0, e1 = v0 - v1, e2 = v2 - v0 (LeafView::e1, e2). Serves one ray against 8
/// triangles (ray broadcast) and 8 rays against one triangle (triangle broadcast). A lane hits
/// when D.Ng != 0, U >= 0, V >= 0, U + V <= |D.Ng| and tnear <= t <= tfar, t finite. The
/// first form takes Ng = e2 x e1 computed once per triangle (by cross_fma: the same bits).
RP_SIMD_INLINE TriHit8 moller_trumbore8(const Vec3x8& org, const Vec3x8& dir, const Vec3x8& v0, const Vec3x8& e1,
                                        const Vec3x8& e2, const Vec3x8& ng, const float8& tnear, const float8& tfar) {
  return mt_answer(mt_terms(org, dir, v0, e1, e2, ng), tnear, tfar);
}

/// The same, with the normal Ng = e2 x e1 computed here (cross_fma, as the scalar routine).
RP_SIMD_INLINE TriHit8 moller_trumbore8(const Vec3x8& org, const Vec3x8& dir, const Vec3x8& v0, const Vec3x8& e1,
                                        const Vec3x8& e2, const float8& tnear, const float8& tfar) {
  return moller_trumbore8(org, dir, v0, e1, e2, simd::cross_fma(e2, e1), tnear, tfar);
}

/// The triangles of a leaf as Vec3x8: corners v0, v1, v2, each coordinate one lookup in the
/// leaf's vertex block (simd::lookup), straight-line code for each number of 8-vertex chunks.
/// Lanes past the leaf's n read whatever index bytes follow the row; v0 and the x of v1 are
/// then set to NaN, which makes every quantity of both triangle tests NaN for those lanes, so
/// they never hit or go to the watertight test's fallback (callers mask them out as well).
struct LeafView {
  Vec3x8 v0, v1, v2;
  /// The leaf read (Leaf(words) is it again). Not a copy of the Leaf: one built field by field
  /// on the stack and copied whole was read back 16 bytes at a time from its 4- and 8-byte
  /// stores, which no store can forward, at every leaf.
  const float* words;
  RP_SIMD_INLINE explicit LeafView(const Leaf& l) : words(l.words) {
    const uint32_t chunks = (l.v + 7) / 8;
    if (chunks == 1)
      read<1>(l);
    else if (chunks == 2)
      read<2>(l);
    else
      read<3>(l);
    const float8 past = simd::nan_past(l.n);
    v0 = {v0.x | past, v0.y | past, v0.z | past};
    v1.x = v1.x | past;
  }
  /// Möller–Trumbore's edges, as rp::intersect_triangle_mt_normal computes them.
  Vec3x8 e1() const { return v0 - v1; }
  Vec3x8 e2() const { return v2 - v0; }

 private:
  template <int Chunks>
  RP_SIMD_INLINE void read(const Leaf& l) {
    const float* x = l.vertices();
    v0 = corner<Chunks>(l, x, 0);
    v1 = corner<Chunks>(l, x, 1);
    v2 = corner<Chunks>(l, x, 2);
  }
  template <int Chunks>
  RP_SIMD_INLINE static Vec3x8 corner(const Leaf& l, const float* x, uint32_t j) {
    const simd::index8<Chunks> i(l.corners(j));
    return {simd::lookup(x, i), simd::lookup(x + l.v, i), simd::lookup(x + 2 * l.v, i)};
  }
};

/// The triangle test of the default variant: Möller–Trumbore (normal-first factoring), its
/// edges computed from the leaf's vertices. Block: a leaf's triangles as the test takes them
/// (edges and normals), made once from the leaf's LeafView for every ray tested against it
/// (a ray stream brings several rays to each leaf it visits on the measured scenes);
/// Single: one ray against a Block; Triangle: one primitive of a leaf in every lane (its lane
/// of the leaf's Block, broadcast); Packet: the 8 rays of a packet against one Triangle.
struct MtKernel {
  struct Block {
    Vec3x8 v0, e1, e2, ng;
    RP_SIMD_INLINE explicit Block(const LeafView& lv)
        : v0(lv.v0), e1(lv.e1()), e2(lv.e2()), ng(simd::cross_fma(e2, e1)) {}
  };
  /// What the watertight kernel learns from a beam of rays (once per beam) and from the origins
  /// of the rays that meet a leaf: nothing here.
  struct Beam {
    Beam() = default;
    explicit Beam(const PacketBeam&) {}
  };
  struct Origins {
    RP_SIMD_INLINE Origins(const Block&, const Beam&) {}
  };
  struct Single {
    Vec3x8 org, dir;
    float8 tnear;
    explicit Single(const Ray& r) : org(r.org), dir(r.dir), tnear(r.tnear) {}
    /// Lane `lane` of packet p (the ray `r`), from the packet's registers.
    Single(const RayPacket& p, int lane, const Ray&)
        : org(p.org.broadcast(lane)), dir(p.dir.broadcast(lane)), tnear(simd::broadcast_lane(p.tnear, lane)) {}
    RP_SIMD_INLINE TriHit8 block(const Block& b, const float8& tfar) const {
      return moller_trumbore8(org, dir, b.v0, b.e1, b.e2, b.ng, tnear, tfar);
    }
    /// The same, for a ray of the beam an Origins was made for.
    RP_SIMD_INLINE TriHit8 block(const Block& b, const float8& tfar, const Origins&) const { return block(b, tfar); }
  };
  struct Triangle {
    Vec3x8 v0, e1, e2, ng;
    Triangle() = default;
    /// Triangle k, whatever the rays' origins.
    RP_SIMD_INLINE Triangle(const Block& b, uint32_t k, const Origins&) : Triangle(b, k) {}
    /// Triangle k of a leaf's Block, in every lane.
    RP_SIMD_INLINE Triangle(const Block& b, uint32_t k)
        : v0(b.v0.broadcast(int(k))),
          e1(b.e1.broadcast(int(k))),
          e2(b.e2.broadcast(int(k))),
          ng(b.ng.broadcast(int(k))) {}
  };
  struct Packet {
    const RayPacket* p = nullptr;
    Packet() = default;
    Packet(const RayPacket& packet, std::span<const Ray>) : p(&packet) {}
    /// The answers of the lanes `lanes` (the caller ignores the others).
    TriHit8 test(const Triangle& t, const float8& tfar, uint32_t /*lanes*/) const {
      return moller_trumbore8(p->org, p->dir, t.v0, t.e1, t.e2, t.ng, p->tnear, tfar);
    }
  };
};

}  // namespace rp::bvh8
