#pragma once
/// What the traversals (traversal.h, large_packet.h) set up per ray and per 8-ray packet: the
/// triangle tests as the traversal calls them (MtKernel for the default variant, CertifiedKernel
/// for the watertight one: one ray against a leaf, or a packet against one triangle), 8 rays
/// loaded into SoA with their valid lanes, the closest hits so far (PacketHits), a packet's
/// one-time set-up (PacketSetup) and the near-first order of a node's children. AVX2+FMA
/// translation units only.

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <span>

#include "backends/simd/bvh8.h"
#include "backends/simd/certified.h"
#include "backends/simd/kernels.h"
#include "engine/ray.h"
#include "simd/float8.h"

namespace rp::bvh8 {

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
  /// What the certified kernel learns from a beam of rays (once per beam) and from the origins
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

/// The triangle test of the watertight variant as it runs: Möller–Trumbore with a bound on
/// the error of each edge decision, settled exactly (rp::edge_side) for the lanes the bound
/// leaves uncertain (certified.h: why every lane's edge decisions are exact).
struct CertifiedKernel {
  /// MtKernel's Block, with the triangles' factors of the bound and the leaf for the settle.
  struct Block : MtKernel::Block {
    EdgeFactors f;      ///< the triangles' factors of the bound (edge_bound8)
    const float* leaf;  ///< the leaf's words, where the settle reads the corners (LeafView::words)
    RP_SIMD_INLINE explicit Block(const LeafView& lv) : MtKernel::Block(lv), f(edge_bound8(e1, e2)), leaf(lv.words) {}
  };
  /// A beam's rays as the bound for rays from one point takes them (once per beam), and a
  /// leaf's triangles against them (SharedOrigin).
  using Beam = OnePoint;
  struct Origins : SharedOrigin {
    RP_SIMD_INLINE Origins(const Block& b, const Beam& beam) : SharedOrigin(b.v0, b.f, beam) {}
  };
  struct Single {
    CertifiedRays r;
    const Ray* ray;  ///< for the settle (a pointer: the ray is copied nowhere on the fast path)
    RP_SIMD_INLINE explicit Single(const Ray& ray_) : r(ray_), ray(&ray_) {}
    Single(const RayPacket& p, int lane, const Ray& ray_)
        : r(p.org.broadcast(lane), p.dir.broadcast(lane), simd::broadcast_lane(p.tnear, lane)), ray(&ray_) {}
    RP_SIMD_INLINE TriHit8 block(const Block& b, const float8& tfar) const {
      TriHit8 h;
      settle(b, tfar, certified_mt8(r, tfar, b.v0, b.e1, b.e2, b.ng, b.f, h), h);
      return h;
    }
    /// The same for a ray of the beam `og` was made for, with its bound where the beam's rays
    /// start at one point (the same answers).
    RP_SIMD_INLINE TriHit8 block(const Block& b, const float8& tfar, const Origins& og) const {
      if (!og.shared) return block(b, tfar);
      TriHit8 h;
      settle(b, tfar, certified_mt8(r.org, r.dir, r.tnear, r.d, tfar, b.v0, b.e1, b.e2, b.ng, og.h, og.g, og.thin, h),
             h);
      return h;
    }

   private:
    /// `h` replaced by the answer with the lanes `unsure` settled, if there are any.
    RP_SIMD_INLINE void settle(const Block& b, const float8& tfar, uint32_t unsure, TriHit8& h) const {
      if (unsure) [[unlikely]] {
        Settled s;
        settle_single(Leaf(b.leaf), *ray, tfar.get(0), unsure, s);
        h = s.w;
      }
    }
  };
  /// MtKernel's Triangle, with the factors of its bound in a, b and thin, and where the settle
  /// reads it. For rays each with their own M: the edge factors xm, xx and x_thin (B =
  /// D (M xm + xx), lanes with |den| < x_thin D thin); for rays from one point (SharedOrigin,
  /// `shared`): its h, g and thin (B = D h + g, lanes with |den| < thin thin).
  struct Triangle : MtKernel::Triangle {
    float8 a, b, thin;
    const float* leaf = nullptr;  ///< the leaf's words, where the settle reads the corners
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
    float8 d;  ///< the rays' max-norms D, their factor in the bound (CertifiedRays)
    Packet() = default;
    Packet(const RayPacket& packet, std::span<const Ray>) : p(&packet), d(max_abs(packet.dir)) {}
    /// The answers of the lanes `lanes` (the caller ignores the others, which therefore never
    /// go to the settle).
    RP_SIMD_INLINE TriHit8 test(const Triangle& t, const float8& tfar, uint32_t lanes) const {
      TriHit8 h;
      const uint32_t unsure =
          (t.shared ? certified_mt8(p->org, p->dir, p->tnear, d, tfar, t.v0, t.e1, t.e2, t.ng, t.a, t.b, t.thin, h)
                    : certified_mt8(p->org, p->dir, p->tnear, d, tfar, t.v0, t.e1, t.e2, t.ng,
                                    EdgeFactors(t.a, t.b, t.thin), h)) &
          lanes;
      if (unsure) [[unlikely]] {
        Settled s;
        settle_packet(*p, tfar, Leaf(t.leaf), t.k, unsure, s);
        h = s.w;
      }
      return h;
    }
  };
};

/// The lanes of 8 rays in SoA that pass rp::valid_ray (engine/ray.h), decided exactly as it
/// decides: every comparison is false for a NaN.
inline uint32_t valid_lanes(const Vec3x8& org, const Vec3x8& dir, const float8& tnear, const float8& tfar) {
  const float8 range(kMaxCoordinate), lo(kMinDirection), hi(kMaxDirection), zero(0.0f);
  const mask8 origin = (xsimd::abs(org.x) <= range) & (xsimd::abs(org.y) <= range) & (xsimd::abs(org.z) <= range);
  const float8 largest = max_abs(dir);
  const mask8 not_nan = (dir.x == dir.x) & (dir.y == dir.y) & (dir.z == dir.z);
  const mask8 direction = (largest >= lo) & (largest <= hi) & not_nan;
  return simd::movemask(origin & direction & (tnear >= zero) & (tnear <= tfar));
}

/// Loads up to 8 rays into `p` with their tfar; invalid rays and missing lanes are inactive
/// (and get harmless values: origin 0, direction (1, 1, 1), tnear 0, tfar -1). Returns the
/// active lanes. Eight rays (32 bytes each, the float fields in the order org, tnear, dir,
/// tfar) load as one 8x8 transpose.
inline uint32_t load_packet(std::span<const Ray> rays, RayPacket& p, float8& tfar) {
  static_assert(sizeof(Ray) == 32 && offsetof(Ray, tnear) == 12 && offsetof(Ray, dir) == 16 && offsetof(Ray, tfar) == 28);
  uint32_t active = 0;
  if (rays.size() >= 8) {
    float8 m[8];
    simd::load_transposed8x8(&rays[0].org.x, m);
    active = valid_lanes({m[0], m[1], m[2]}, {m[4], m[5], m[6]}, m[3], m[7]);
    const mask8 on = simd::mask_from_bits(active);
    const float8 zero(0.0f), one(1.0f);
    p.org = {xsimd::select(on, m[0], zero), xsimd::select(on, m[1], zero), xsimd::select(on, m[2], zero)};
    p.dir = {xsimd::select(on, m[4], one), xsimd::select(on, m[5], one), xsimd::select(on, m[6], one)};
    p.tnear = xsimd::select(on, m[3], zero);
    tfar = xsimd::select(on, m[7], float8(-1.0f));
  } else {
    simd::Spill<8> s;
    auto& [ox, oy, oz, dx, dy, dz, tn, tf] = s.lanes;
    for (size_t i = 0; i < 8; ++i) {
      const bool ok = i < rays.size() && valid_ray(rays[i]);
      const Ray r = ok ? rays[i] : Ray{{0.0f, 0.0f, 0.0f}, 0.0f, {1.0f, 1.0f, 1.0f}, -1.0f};
      ox[i] = r.org.x; oy[i] = r.org.y; oz[i] = r.org.z;
      dx[i] = r.dir.x; dy[i] = r.dir.y; dz[i] = r.dir.z;
      tn[i] = r.tnear; tf[i] = r.tfar;
      active |= uint32_t(ok) << i;
    }
    p.org = {s.load(0), s.load(1), s.load(2)};
    p.dir = {s.load(3), s.load(4), s.load(5)};
    p.tnear = s.load(6);
    tfar = s.load(7);
  }
  const float8 one(1.0f);
  p.inv = {one / p.dir.x, one / p.dir.y, one / p.dir.z};
  // Sign bit, so that -0 (inverse -inf) takes the far plane first like a negative direction.
  p.neg_x = simd::sign_mask(p.dir.x);
  p.neg_y = simd::sign_mask(p.dir.y);
  p.neg_z = simd::sign_mask(p.dir.z);
  p.oi = {p.org.x * p.inv.x, p.org.y * p.inv.y, p.org.z * p.inv.z};
  p.abs_pad = xsimd::max(xsimd::abs(p.oi.x), xsimd::max(xsimd::abs(p.oi.y), xsimd::abs(p.oi.z))) * float8(0x1p-23f);
  return active;
}

/// The closest hits found so far for the 8 lanes of a packet: t (the lane's tfar), u, v, the
/// primitive (kInvalidId for none) and its instance (kNoInstance for none). The world's tree
/// is traversed before the instances' (simd_backend.cpp), so only an instance's traversal
/// writes `inst`.
struct PacketHits {
  float8 tfar, u, v;
  alignas(32) uint32_t prim[8];
  alignas(32) uint32_t inst[8];

  /// No hit in any lane (tfar is left to the caller).
  void clear() {
    std::fill_n(prim, 8, kInvalidId);
    std::fill_n(inst, 8, kNoInstance);
    u = v = float8(0.0f);
  }

  /// Runs f(lane, hit) for each lane of `mask` on that lane's closest hit as a scalar Hit
  /// (t = the lane's tfar), which f may improve: the lanes are stored once, then reloaded.
  template <class F>
  void each_lane(uint32_t mask, F&& f) {
    simd::Spill<3> s(tfar, u, v);
    auto& [tf, uu, vv] = s.lanes;
    for (uint32_t b = mask; b; b &= b - 1) {
      const int lane = std::countr_zero(b);
      Hit hit{tf[lane], prim[lane], uu[lane], vv[lane], inst[lane]};
      f(lane, hit);
      tf[lane] = hit.t;
      uu[lane] = hit.u;
      vv[lane] = hit.v;
      prim[lane] = hit.prim_id;
      inst[lane] = hit.instance_id;
    }
    tfar = s.load(0);
    u = s.load(1);
    v = s.load(2);
  }
};

/// What a packet traversal sets up once: the kernel's per-packet data, the direction signs
/// that order children near-first, the beam that culls them and what the kernel takes of it.
template <class Kernel>
struct PacketSetup {
  typename Kernel::Packet kp;
  float8 sx, sy, sz;
  PacketBeam beam;
  typename Kernel::Beam kbeam;
  PacketSetup() = default;
  PacketSetup(const RayPacket& p, std::span<const Ray> rays, uint32_t active)
      : kp(p, rays), beam(p, active), kbeam(beam) {
    // The packet's direction signs from its first active ray, as +-1 per axis.
    const Vec3f d = p.dir.lane(std::countr_zero(active));
    sx = float8(std::signbit(d.x) ? -1.0f : 1.0f);
    sy = float8(std::signbit(d.y) ? -1.0f : 1.0f);
    sz = float8(std::signbit(d.z) ? -1.0f : 1.0f);
  }
};

/// The keys that order a node's children near-first along direction signs (sx, sy, sz): sum
/// over axes of sign * (lo + hi), one 8-wide op; the nearest child has the smallest key.
inline float8 near_first_keys(const Bvh8Node& n, const float8& sx, const float8& sy, const float8& sz) {
  return sx * (float8::load_aligned(n.lo_x) + float8::load_aligned(n.hi_x)) +
         sy * (float8::load_aligned(n.lo_y) + float8::load_aligned(n.hi_y)) +
         sz * (float8::load_aligned(n.lo_z) + float8::load_aligned(n.hi_z));
}

}  // namespace rp::bvh8
