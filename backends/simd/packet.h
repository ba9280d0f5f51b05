#pragma once
/// 8-ray packets as the simd backend's traversal loops keep them: rays loaded into SoA with
/// their valid lanes (load_packet), the closest hits found so far (PacketHits), and a
/// packet's one-time set-up (PacketSetup). AVX2+FMA translation units only.

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <span>

#include "backends/simd/slab.h"
#include "core/ray.h"

namespace rp::bvh8 {

/// The lanes of 8 rays in SoA that pass rp::valid_ray (core/ray.h), decided exactly as it
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

}  // namespace rp::bvh8
