#include "backends/simd/simd_backend.h"

#include <algorithm>
#include <bit>
#include <cmath>

#include "backends/simd/bvh8.h"
#include "backends/simd/kernels.h"
#include "engine/error.h"

namespace rp::bvh8 {

namespace {

using simd::float8;
using simd::mask8;
using simd::movemask;
using simd::Vec3x8;

/// Traversal stack bound: the build keeps binary depth <= 64 + log2(n) < 100, so an 8-wide
/// tree holds at most 7 pending children per level.
constexpr int kStackSize = 1024;

/// A packet entry with at most this many active lanes continues as single rays.
constexpr int kSingleRayLanes = 2;

/// Primitive k of a leaf of n: rows `row`, `row` + 1, `row` + 2 (see Tri8), in every lane.
inline Vec3x8 row3(const float* rows, uint32_t n, uint32_t row, uint32_t k) {
  return Vec3x8(Vec3f{rows[row * n + k], rows[(row + 1) * n + k], rows[(row + 2) * n + k]});
}

/// The triangle test of the default variant: Möller–Trumbore (normal-first factoring) on the
/// edge layout. Single: one ray against a leaf's primitives; Packet: the 8 rays of a packet
/// against one primitive.
struct MtKernel {
  static constexpr TriangleLayout kLayout = TriangleLayout::edges;
  struct Single {
    Vec3x8 org, dir;
    float8 tnear;
    explicit Single(const Ray& r) : org(r.org), dir(r.dir), tnear(r.tnear) {}
    Mt8 block(const float* rows, uint32_t n, const float8& tfar) const {
      const LeafView lv(rows, n);
      return moller_trumbore8(org, dir, lv.v0, lv.p1, lv.p2, tnear, tfar);
    }
  };
  struct Packet {
    const RayPacket& p;
    Packet(const RayPacket& packet, std::span<const Ray>) : p(packet) {}
    Mt8 slot(const float* rows, uint32_t n, uint32_t k, const float8& tfar) const {
      return moller_trumbore8(p.org, p.dir, row3(rows, n, 0, k), row3(rows, n, 3, k), row3(rows, n, 6, k), p.tnear,
                              tfar);
    }
  };
};

/// The triangle test of the watertight variant (Woop, Benthin and Wald 2013) on the vertex
/// layout; the traversal around it is the same conservative one.
struct WatertightKernel {
  static constexpr TriangleLayout kLayout = TriangleLayout::vertices;
  struct Single {
    WatertightRays r;
    explicit Single(const Ray& ray) : r(&ray, 1) {}
    Mt8 block(const float* rows, uint32_t n, const float8& tfar) const {
      const LeafView lv(rows, n);
      return watertight8(r, lv.v0, lv.p1, lv.p2, tfar);
    }
  };
  struct Packet {
    WatertightRays r;
    Packet(const RayPacket&, std::span<const Ray> rays) : r(rays.data(), rays.size()) {}
    Mt8 slot(const float* rows, uint32_t n, uint32_t k, const float8& tfar) const {
      return watertight8(r, row3(rows, n, 0, k), row3(rows, n, 3, k), row3(rows, n, 6, k), tfar);
    }
  };
};

template <class Kernel>
class SimdBackend final : public Backend {
 public:
  SimdBackend(const Scene& scene, const std::string& variant, SplitRule rule) : scene_(scene) {
    BuildOptions bo;
    bo.rule = rule;
    bo.layout = Kernel::kLayout;
    bvh_ = build(scene, bo);
    info_.name = "simd";
    info_.variant = variant;
    info_.build_seconds = bvh_.stats.seconds;
    info_.bytes = bvh_.stats.bytes;
    info_.stats = {{"nodes", double(bvh_.stats.nodes)},  {"leaves", double(bvh_.stats.leaves)},
                   {"depth", double(bvh_.stats.depth)},  {"sah_cost", bvh_.stats.sah_cost},
                   {"prims", double(bvh_.stats.prims)}};
  }

  void intersect(std::span<const Ray> rays, std::span<Hit> hits, Coherence coherence) const noexcept override {
    if (coherence == Coherence::coherent) {
      for (size_t base = 0; base < rays.size(); base += 8)
        intersect_packet(rays.subspan(base, std::min<size_t>(8, rays.size() - base)), hits.subspan(base));
    } else {
      for (size_t i = 0; i < rays.size(); ++i) hits[i] = intersect_single(rays[i]);
    }
  }

  void occluded(std::span<const Ray> rays, std::span<uint8_t> out, Coherence coherence) const noexcept override {
    if (coherence == Coherence::coherent) {
      for (size_t base = 0; base < rays.size(); base += 8)
        occluded_packet(rays.subspan(base, std::min<size_t>(8, rays.size() - base)), out.subspan(base));
    } else {
      for (size_t i = 0; i < rays.size(); ++i) out[i] = valid_ray(rays[i]) && occluded_single(rays[i]);
    }
  }

  const BackendInfo& info() const noexcept override { return info_; }

 private:
  // ---- single ray: one ray against the 8 children of a node ----

  /// Starts loading the nodes (or leaf blocks) of the children in `bits`, which traversal is
  /// about to visit or push: hides part of the memory latency that dominates traversal.
  void prefetch_children(const Bvh8Node& n, uint32_t bits) const noexcept {
    for (; bits; bits &= bits - 1) {
      const int32_t c = n.child[std::countr_zero(bits)];
      if (is_leaf(c)) {  // 40 bytes per primitive, from anywhere in a line
        const char* p = reinterpret_cast<const char*>(bvh_.leaf(leaf_first(c)));
        const uint32_t bytes = 40 * leaf_count(c);
        for (uint32_t off = 0; off < bytes; off += 64) _mm_prefetch(p + off, _MM_HINT_T0);
        _mm_prefetch(p + bytes - 1, _MM_HINT_T0);
      } else {
        const char* p = reinterpret_cast<const char*>(&bvh_.nodes[size_t(c)]);
        _mm_prefetch(p, _MM_HINT_T0);
        _mm_prefetch(p + 64, _MM_HINT_T0);
        _mm_prefetch(p + 128, _MM_HINT_T0);
        _mm_prefetch(p + 192, _MM_HINT_T0);
      }
    }
  }

  /// The prim_id of the leaf of n at `rows` when it is an analytic primitive, else
  /// kInvalidId. The build gives an analytic primitive a leaf of its own, so a leaf is all
  /// triangles (one 8-wide test) or one analytic primitive (its scalar routine).
  uint32_t analytic_leaf(const float* rows, uint32_t n) const noexcept {
    if (n != 1 || !bvh_.has_analytic) return kInvalidId;
    const uint32_t id = prim_at(rows, 1, 0);
    return id >= bvh_.first_analytic ? id : kInvalidId;
  }
  static uint32_t prim_at(const float* rows, uint32_t n, uint32_t k) { return std::bit_cast<uint32_t>(rows[9 * n + k]); }

  /// Closest hit of one ray.
  Hit intersect_single(const Ray& r) const noexcept {
    Hit best;
    if (!valid_ray(r)) return best;
    if (!bvh_.empty()) traverse_closest(r, 0, best);
    scene_.intersect_planes(r, best);
    return best;
  }

  /// Closest hit of a valid ray in the subtree `root`, replacing `best` by any hit within
  /// [tnear, min(tfar, best.t)]. Children are visited near-first by their entry distance, the
  /// far ones pushed first; popped entries farther than the current hit are skipped.
  void traverse_closest(const Ray& r, int32_t root, Hit& best) const noexcept {
    float tfar = std::min(r.tfar, best.t);
    {
      const SingleRay sr(r);
      const typename Kernel::Single kr(r);
      struct Entry { int32_t ref; float t; };
      Entry stack[kStackSize];
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
              stack[sp++] = {n.child[far], dist[far]};
              ref = n.child[near];
              continue;
            }
            prefetch_children(n, bits);
            // Onto the stack in slot order, then sorted there by descending distance (a stable
            // insertion sort: ties keep the higher slot nearer the top); the nearest is visited.
            Entry* hit = stack + sp;
            int k = 0;
            for (; bits; bits &= bits - 1) {
              const int c = std::countr_zero(bits);
              const Entry e{n.child[c], dist[c]};
              int j = k++;
              for (; j > 0 && hit[j - 1].t < e.t; --j) hit[j] = hit[j - 1];
              hit[j] = e;
            }
            sp += k - 1;
            ref = hit[k - 1].ref;
            continue;
          }
        } else {
          const uint32_t n = leaf_count(ref);
          const float* rows = bvh_.leaf(leaf_first(ref));
          if (const uint32_t id = analytic_leaf(rows, n); id != kInvalidId) {
            Ray rr = r;
            rr.tfar = tfar;
            const Intersection<float> ah = scene_.intersect_analytic(id, rr);
            if (ah.hit) {
              tfar = ah.t;
              best = {ah.t, id, ah.u, ah.v};
            }
          } else {
            const Mt8 h = kr.block(rows, n, float8(tfar));
            if (const uint32_t bits = movemask(h.hit) & ((1u << n) - 1)) {
              const float tmin = simd::reduce_min(
                  xsimd::select(simd::mask_from_bits(bits), h.t, float8(std::numeric_limits<float>::infinity())));
              const uint32_t at_min = movemask(h.t == float8(tmin)) & bits;
              const int lane = 31 - std::countl_zero(at_min);  // ties: the last, as the packet path
              alignas(32) float u[8], v[8];
              h.u.store_aligned(u);
              h.v.store_aligned(v);
              tfar = tmin;
              best = {tmin, prim_at(rows, n, uint32_t(lane)), u[lane], v[lane]};
            }
          }
        }
        for (;;) {  // pop, skipping subtrees entered beyond the current hit
          if (sp == 0) return;
          const Entry e = stack[--sp];
          if (e.t <= std::fma(tfar, kSlabPad, sr.pad)) {  // conservative, as intersect_node
            ref = e.ref;
            break;
          }
        }
      }
    }
  }

  /// Any hit of one (valid) ray; stops at the first.
  bool occluded_single(const Ray& r) const noexcept {
    if (scene_.occluded_by_planes(r)) return true;
    return !bvh_.empty() && traverse_any(r, 0);
  }

  /// Any hit of a valid ray in the subtree `root`.
  bool traverse_any(const Ray& r, int32_t root) const noexcept {
    const SingleRay sr(r);
    const typename Kernel::Single kr(r);
    const float8 tfar8(r.tfar);
    int32_t stack[kStackSize];
    int sp = 0;
    stack[sp++] = root;
    while (sp > 0) {
      const int32_t ref = stack[--sp];
      if (!is_leaf(ref)) {
        const Bvh8Node& n = bvh_.nodes[size_t(ref)];
        float8 t_enter;
        for (uint32_t bits = intersect_node(n, sr, r.tnear, r.tfar, t_enter); bits; bits &= bits - 1)
          stack[sp++] = n.child[std::countr_zero(bits)];
        continue;
      }
      const uint32_t n = leaf_count(ref);
      const float* rows = bvh_.leaf(leaf_first(ref));
      if (const uint32_t id = analytic_leaf(rows, n); id != kInvalidId) {
        if (scene_.intersect_analytic(id, r).hit) return true;
      } else if (movemask(kr.block(rows, n, tfar8).hit) & ((1u << n) - 1)) {
        return true;
      }
    }
    return false;
  }

  // ---- packets: 8 rays against one node's boxes ----

  /// Loads up to 8 rays; invalid rays and missing lanes are inactive (and get harmless values).
  static uint32_t load_packet(std::span<const Ray> rays, RayPacket& p, float8& tfar) {
    alignas(32) float ox[8], oy[8], oz[8], dx[8], dy[8], dz[8], tn[8], tf[8];
    uint32_t active = 0;
    for (size_t i = 0; i < 8; ++i) {
      const bool ok = i < rays.size() && valid_ray(rays[i]);
      const Ray r = ok ? rays[i] : Ray{{0.0f, 0.0f, 0.0f}, 0.0f, {1.0f, 1.0f, 1.0f}, -1.0f};
      ox[i] = r.org.x; oy[i] = r.org.y; oz[i] = r.org.z;
      dx[i] = r.dir.x; dy[i] = r.dir.y; dz[i] = r.dir.z;
      tn[i] = r.tnear; tf[i] = r.tfar;
      active |= uint32_t(ok) << i;
    }
    p.org = Vec3x8::load(ox, oy, oz);
    p.dir = Vec3x8::load(dx, dy, dz);
    const float8 one(1.0f);
    p.inv = {one / p.dir.x, one / p.dir.y, one / p.dir.z};
    // Sign bit, so that -0 (inverse -inf) takes the far plane first like a negative direction.
    p.neg_x = simd::sign_mask(p.dir.x);
    p.neg_y = simd::sign_mask(p.dir.y);
    p.neg_z = simd::sign_mask(p.dir.z);
    p.tnear = float8::load_aligned(tn);
    p.oi = {p.org.x * p.inv.x, p.org.y * p.inv.y, p.org.z * p.inv.z};
    p.abs_pad = xsimd::max(xsimd::abs(p.oi.x), xsimd::max(xsimd::abs(p.oi.y), xsimd::abs(p.oi.z))) * float8(0x1p-23f);
    tfar = float8::load_aligned(tf);
    return active;
  }

  /// What a packet traversal sets up once: the kernel's per-packet data, the direction signs
  /// that order children near-first, and the beam that culls them.
  struct PacketSetup {
    typename Kernel::Packet kp;
    float8 sx, sy, sz;
    PacketBeam beam;
    PacketSetup(const RayPacket& p, std::span<const Ray> rays, uint32_t active) : kp(p, rays), beam(p, active) {
      packet_signs(p, active, sx, sy, sz);
    }
  };
  struct PacketEntry {
    int32_t ref;
    uint32_t mask;
  };

  /// Children of `n` hit by any lane of `mask`, ordered near-first along the packet's
  /// direction signs (the key sum_a sign_a (lo_a + hi_a) of each child, one 8-wide op).
  struct Child { int32_t ref; uint32_t mask; float key; };
  static int ordered_children(const Bvh8Node& n, const RayPacket& p, const PacketSetup& ps, const float8& tfar,
                              uint32_t mask, Child* out) {
    const PacketBeam& beam = ps.beam;
    const float8 &sign_x = ps.sx, &sign_y = ps.sy, &sign_z = ps.sz;
    uint32_t candidates = 0xffu;
    if (beam.valid)
      candidates = beam.cull(n, simd::reduce_max(xsimd::select(simd::mask_from_bits(mask), tfar, float8(0.0f))));
    const float8 key8 = sign_x * (float8::load_aligned(n.lo_x) + float8::load_aligned(n.hi_x)) +
                        sign_y * (float8::load_aligned(n.lo_y) + float8::load_aligned(n.hi_y)) +
                        sign_z * (float8::load_aligned(n.lo_z) + float8::load_aligned(n.hi_z));
    alignas(32) float key[8];
    key8.store_aligned(key);
    int k = 0;
    for (int c = 0; c < 8 && n.child[c] != kEmpty; ++c) {
      if (!(candidates >> c & 1u)) continue;
      const Vec3f lo{n.lo_x[c], n.lo_y[c], n.lo_z[c]}, hi{n.hi_x[c], n.hi_y[c], n.hi_z[c]};
      const uint32_t m = (beam.valid ? intersect_box_octant(p, beam.neg, lo, hi, tfar) : intersect_box(p, lo, hi, tfar)) & mask;
      if (!m) continue;
      Child e{n.child[c], m, key[c]};
      int j = k++;
      for (; j > 0 && out[j - 1].key < e.key; --j) out[j] = out[j - 1];  // descending: nearest last
      out[j] = e;
    }
    return k;
  }

  /// The packet's direction signs from its first active ray, as +-1 per axis.
  static void packet_signs(const RayPacket& p, uint32_t active, float8& sx, float8& sy, float8& sz) {
    const int lane = std::countr_zero(active);
    const Vec3f d = p.dir.lane(lane);
    sx = float8(std::signbit(d.x) ? -1.0f : 1.0f);
    sy = float8(std::signbit(d.y) ? -1.0f : 1.0f);
    sz = float8(std::signbit(d.z) ? -1.0f : 1.0f);
  }

  /// The lanes of `mask` through the subtree `ref` one ray at a time: a packet whose rays
  /// have drifted apart costs 8 lanes of work per box and triangle for one or two useful
  /// ones, so below kSingleRayLanes active lanes the packet hands its rays to the single-ray
  /// traversal (Benthin et al., "Combining Single and Packet-Ray Tracing for Arbitrary Ray
  /// Distributions on the Intel MIC Architecture", IEEE TVCG 18(9), 2012).
  void single_rays_closest(int32_t ref, uint32_t mask, std::span<const Ray> rays, float8& tfar, float8& u, float8& v,
                           uint32_t* prim) const noexcept {
    alignas(32) float tf[8], uu[8], vv[8];
    tfar.store_aligned(tf);
    u.store_aligned(uu);
    v.store_aligned(vv);
    for (uint32_t b = mask; b; b &= b - 1) {
      const int lane = std::countr_zero(b);
      Hit h{tf[lane], prim[lane], uu[lane], vv[lane]};
      traverse_closest(rays[size_t(lane)], ref, h);
      tf[lane] = h.t;
      uu[lane] = h.u;
      vv[lane] = h.v;
      prim[lane] = h.prim_id;
    }
    tfar = float8::load_aligned(tf);
    u = float8::load_aligned(uu);
    v = float8::load_aligned(vv);
  }

  /// Analytic primitive `id` against the lanes of `mask`, by its scalar routine.
  void analytic_packet(uint32_t id, std::span<const Ray> rays, uint32_t mask, float8& tfar, float8& u, float8& v,
                       uint32_t* prim) const noexcept {
    alignas(32) float tf[8], uu[8], vv[8];
    tfar.store_aligned(tf);
    u.store_aligned(uu);
    v.store_aligned(vv);
    for (uint32_t b = mask; b; b &= b - 1) {
      const int lane = std::countr_zero(b);
      Ray r = rays[size_t(lane)];
      r.tfar = tf[lane];
      const Intersection<float> h = scene_.intersect_analytic(id, r);
      if (h.hit) {
        tf[lane] = h.t;
        uu[lane] = h.u;
        vv[lane] = h.v;
        prim[lane] = id;
      }
    }
    tfar = float8::load_aligned(tf);
    u = float8::load_aligned(uu);
    v = float8::load_aligned(vv);
  }

  void intersect_packet(std::span<const Ray> rays, std::span<Hit> hits) const noexcept {
    RayPacket p;
    float8 tfar;
    const uint32_t active = load_packet(rays, p, tfar);
    alignas(32) uint32_t prim[8];
    std::fill_n(prim, 8, kInvalidId);
    float8 u(0.0f), v(0.0f);
    if (active && !bvh_.empty()) {
      const PacketSetup ps(p, rays, active);
      PacketEntry stack[kStackSize];
      int sp = 0;
      stack[sp++] = {0, active};
      while (sp > 0) {
        const PacketEntry e = stack[--sp];
        if (simd::lane_count(e.mask) <= kSingleRayLanes) {
          single_rays_closest(e.ref, e.mask, rays, tfar, u, v, prim);
          continue;
        }
        if (!is_leaf(e.ref)) {
          Child kids[8];
          const int k = ordered_children(bvh_.nodes[size_t(e.ref)], p, ps, tfar, e.mask, kids);
          for (int j = 0; j < k; ++j) stack[sp++] = {kids[j].ref, kids[j].mask};
          continue;
        }
        const mask8 lanes = simd::mask_from_bits(e.mask);
        const uint32_t n = leaf_count(e.ref);
        const float* rows = bvh_.leaf(leaf_first(e.ref));
        for (uint32_t k = 0; k < n; ++k) {
          const uint32_t id = prim_at(rows, n, k);
          if (id >= bvh_.first_analytic) {
            analytic_packet(id, rays, e.mask, tfar, u, v, prim);
            continue;
          }
          const Mt8 h = ps.kp.slot(rows, n, k, tfar);
          const mask8 upd = h.hit & lanes;
          const uint32_t bits = movemask(upd);
          if (!bits) continue;
          tfar = xsimd::select(upd, h.t, tfar);
          u = xsimd::select(upd, h.u, u);
          v = xsimd::select(upd, h.v, v);
          for (uint32_t b = bits; b; b &= b - 1) prim[std::countr_zero(b)] = id;
        }
      }
    }
    alignas(32) float tf[8], uu[8], vv[8];
    tfar.store_aligned(tf);
    u.store_aligned(uu);
    v.store_aligned(vv);
    for (size_t i = 0; i < rays.size(); ++i) {  // field by field: no 16-byte reload of a Hit built in pieces
      Hit& h = hits[i];
      const bool hit = prim[i] != kInvalidId;  // an inactive lane never gets a primitive
      h.t = hit ? tf[i] : std::numeric_limits<float>::infinity();
      h.prim_id = prim[i];
      h.u = hit ? uu[i] : 0.0f;
      h.v = hit ? vv[i] : 0.0f;
      if (active >> i & 1u) scene_.intersect_planes(rays[i], h);
    }
  }

  void occluded_packet(std::span<const Ray> rays, std::span<uint8_t> out) const noexcept {
    RayPacket p;
    float8 tfar;
    uint32_t active = load_packet(rays, p, tfar);
    uint32_t done = 0;
    for (uint32_t b = active; b; b &= b - 1) {
      const int lane = std::countr_zero(b);
      if (scene_.occluded_by_planes(rays[size_t(lane)])) done |= 1u << lane;
    }
    uint32_t live = active & ~done;
    if (live && !bvh_.empty()) {
      const PacketSetup ps(p, rays, live);
      PacketEntry stack[kStackSize];
      int sp = 0;
      stack[sp++] = {0, live};
      while (sp > 0 && live) {  // early exit once every lane is occluded
        PacketEntry e = stack[--sp];
        e.mask &= live;
        if (!e.mask) continue;
        if (simd::lane_count(e.mask) <= kSingleRayLanes) {
          for (uint32_t b = e.mask; b; b &= b - 1)
            if (traverse_any(rays[size_t(std::countr_zero(b))], e.ref)) done |= b & (~b + 1);
          live = active & ~done;
          continue;
        }
        if (!is_leaf(e.ref)) {
          Child kids[8];
          const int k = ordered_children(bvh_.nodes[size_t(e.ref)], p, ps, tfar, e.mask, kids);
          for (int j = 0; j < k; ++j) stack[sp++] = {kids[j].ref, kids[j].mask};
          continue;
        }
        const uint32_t n = leaf_count(e.ref);
        const float* rows = bvh_.leaf(leaf_first(e.ref));
        for (uint32_t k = 0; k < n && e.mask; ++k) {
          const uint32_t id = prim_at(rows, n, k);
          uint32_t hit = 0;
          if (id >= bvh_.first_analytic) {
            for (uint32_t b = e.mask; b; b &= b - 1)
              if (scene_.intersect_analytic(id, rays[size_t(std::countr_zero(b))]).hit) hit |= b & -b;
          } else {
            const Mt8 h = ps.kp.slot(rows, n, k, tfar);
            hit = movemask(h.hit) & e.mask;
          }
          done |= hit;
          e.mask &= ~hit;
        }
        live = active & ~done;
      }
    }
    for (size_t i = 0; i < rays.size(); ++i) out[i] = uint8_t(done >> i & 1u);
  }

  const Scene& scene_;
  Bvh8 bvh_;
  BackendInfo info_;
};

}  // namespace

std::vector<std::string> variants() { return {"default", "median", "watertight"}; }

std::unique_ptr<Backend> make_backend(const Scene& scene, const BackendOptions& options) {
  const std::string& v = options.variant;
  if (v == "default") return std::make_unique<SimdBackend<MtKernel>>(scene, v, SplitRule::sah);
  if (v == "median") return std::make_unique<SimdBackend<MtKernel>>(scene, v, SplitRule::median);
  if (v == "watertight") return std::make_unique<SimdBackend<WatertightKernel>>(scene, v, SplitRule::sah);
  throw Error(cat("simd: unknown variant '", v, "' (default, median, watertight)"));
}

}  // namespace rp::bvh8
