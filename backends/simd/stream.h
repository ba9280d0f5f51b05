#pragma once
/// Ray-stream traversal for incoherent batches (a renderer's bounces, `trace`, `diff`, the
/// bench's diffuse rays; Backend::intersect and occluded with Coherence::incoherent), after
/// Barringer and Akenine-Möller, "Dynamic Ray Stream Traversal", ACM TOG 33(4), 2014: the
/// batch goes down the tree as a stream of ray ids. At an inner node every ray of the stream
/// takes the single-ray slab test against the node's 8 child boxes (pass 1, no branch on the
/// outcome), then the stream is split into one stream per child (pass 2, the ids compressed 8
/// at a time); the children are visited near-first along the stream's mean direction, each
/// with its own stream. At a leaf the vertex block is decoded once for the whole stream and
/// every ray takes the single-ray triangle test. A stream of fewer than kMinStream rays, and
/// a leaf holding an analytic primitive, go on ray by ray (single_ray.h, from that node).
///
/// One loop (trace_stream) for both levels (levels.h) and every query (the stream policies
/// below, over queries.h): in a scene with instances the batch then goes down the instance
/// tree as a stream the same way; at an instance, the rays of its stream are mapped into its
/// object space (rp::object_ray, the single-ray path's bits) and traced through the mesh's
/// tree as a stream of their own, with the answers found so far (the map keeps t the world t).
///
/// Why it pays over tracing the rays one by one: a ray alone walks the tree as a chain of
/// dependent loads and branches no predictor can guess (how many children were hit, node or
/// leaf), which leaves most of the core idle; the stream's loops run the same test for many
/// rays, a node's boxes and a leaf's decoded triangles are reused from L1 by every ray of the
/// stream, and the children's nodes are fetched while the nearest one is worked on. What it
/// gives up is each ray's own near-first order: a ray may enter a subtree before the one
/// holding its hit. A stream is tested with its rays' current tfar when it is popped, so a ray
/// whose hit was found meanwhile drops out at the next node. Any-hit queries need no order,
/// and a ray leaves every stream once it is occluded.
///
/// Answers are those of the single-ray traversal, bit for bit: the same slab test (one-FMA
/// form; rays that need the exact form, SlabRay::exact, are traced alone), the same
/// triangle test, and hits resolved by the rule of levels.h (the least (t, prim_id)), which
/// does not depend on the order leaves are met. AVX2+FMA translation units only.

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "backends/simd/traversal.h"

namespace rp::bvh8 {

/// A stream with fewer rays than this goes on ray by ray from its node. (2, 4 and 8 measured
/// alike on diffuse rays; figures: docs/notes/2026-11-29-figures-from-code-comments.md.)
inline constexpr uint32_t kMinStream = 4;

/// Rays in one stream at most: a longer batch is cut into streams of this many, so the rays'
/// state stays in L2 and a thread's buffers stay small. (Measured on diffuse rays against
/// rtcIntersect1 in the first version: streams of 2,048 to 4,096 rays did best, longer ones
/// lost speed, and the whole batch as one stream lost most on Sponza; figures:
/// docs/notes/2026-11-29-figures-from-code-comments.md.)
inline constexpr size_t kMaxStream = 4096;

template <class Kernel>
class StreamTraversal {
 public:
  explicit StreamTraversal(const Traversal<Kernel>& t) : t_(t) {}

  /// Closest hits of a batch of rays, the planes included.
  void intersect(std::span<const Ray> rays, std::span<Hit> hits) const noexcept {
    for (size_t base = 0; base < rays.size(); base += kMaxStream) {
      const size_t n = std::min(kMaxStream, rays.size() - base);
      intersect_stream(rays.subspan(base, n), hits.subspan(base, n));
    }
  }

  /// Any hits of a batch of rays, the planes included.
  void occluded(std::span<const Ray> rays, std::span<uint8_t> out) const noexcept {
    for (size_t base = 0; base < rays.size(); base += kMaxStream) {
      const size_t n = std::min(kMaxStream, rays.size() - base);
      occluded_stream(rays.subspan(base, n), out.subspan(base, n));
    }
  }

 private:
  /// What the node test reads of a stream ray.
  struct StreamRay {
    SlabRay slab;
    float tnear;  ///< >= +0
    float tfar;   ///< the closest hit so far, or the ray's tfar (-inf once occluded)
  };
  /// A subtree and the stream of rays that still have to visit it: ids[begin, begin + count);
  /// the streams of its children go from `top` (everything above it is free once this frame
  /// is popped).
  struct Frame {
    int32_t ref;
    uint32_t begin, count, top;
  };
  /// A thread's buffers, reused from batch to batch.
  struct Scratch {
    std::vector<StreamRay> rays;
    std::vector<uint32_t> ids;  ///< every pending stream, back to back
    std::vector<uint8_t> bits;  ///< each ray's hit mask at the node being split
    std::vector<Frame> frames;
  };
  /// A thread's buffers: depth 0 for the world's tree and the instance tree, 1 for an
  /// instance's mesh (traced while the instance level's stream waits).
  static Scratch& scratch(int level) {
    static thread_local Scratch s[2];
    return s[level];
  }

  /// Closest hits of one stream (at most kMaxStream rays).
  void intersect_stream(std::span<const Ray> rays, std::span<Hit> hits) const noexcept {
    // Each ray's t is its tfar until a primitive is found. An invalid ray never enters a
    // stream (enter_all decides validity), so it stays without a primitive and ends a miss;
    // validity is checked here only before the planes, and only in a scene with planes.
    for (size_t i = 0; i < rays.size(); ++i) {
      hits[i] = Hit{};
      hits[i].t = rays[i].tfar;
    }
    ClosestStream q{rays, hits};
    trace_stream(t_.world(), rays, q, scratch(0));
    if (const InstanceLevel<Kernel>* in = t_.instances()) trace_stream(*in, rays, q, scratch(0));
    const bool planes = !t_.scene().planes().empty();
    for (size_t i = 0; i < rays.size(); ++i) {
      if (!hits[i].hit()) hits[i] = Hit{};
      if (planes && valid_ray(rays[i])) t_.scene().intersect_planes(rays[i], hits[i]);
    }
  }

  /// Any hits of one stream.
  void occluded_stream(std::span<const Ray> rays, std::span<uint8_t> out) const noexcept {
    // Planes first: in a scene without any, validity is left to enter_all.
    for (size_t i = 0; i < rays.size(); ++i) out[i] = t_.scene().occluded_by_planes(rays[i]) && valid_ray(rays[i]);
    AnyStream q{rays, out};
    trace_stream(t_.world(), rays, q, scratch(0));
    if (const InstanceLevel<Kernel>* in = t_.instances()) trace_stream(*in, rays, q, scratch(0));
  }

  /// The valid rays of `rays` that query `q` still needs (q.skip) as one stream through level
  /// `lv`: the one loop of the stream shape. A ray that needs the exact slab form
  /// (SlabRay::exact), a stream of fewer than kMinStream rays and a leaf holding an analytic
  /// primitive go on ray by ray (q.single, single_ray.h).
  template <class Level, class Q>
  static void trace_stream(const Level& lv, std::span<const Ray> rays, Q& q, Scratch& s) noexcept {
    if (lv.empty()) return;
    prepare(rays.size(), s);
    const uint32_t count = enter_all(rays, s, q, [&](size_t i) { q.single(lv, i, SingleRay(rays[i]), 0); });
    if (count) s.frames.push_back({0, 0, count, count});
    while (!s.frames.empty()) {
      const Frame f = s.frames.back();
      s.frames.pop_back();
      if (f.count < kMinStream || (is_leaf(f.ref) && analytic(lv, f.ref))) {
        for (uint32_t k = 0; k < f.count; ++k) {
          const uint32_t i = s.ids[f.begin + k];
          s.rays[i].tfar = q.single(lv, i, SingleRay(rays[i], s.rays[i].slab), f.ref);
        }
      } else if (is_leaf(f.ref)) {
        stream_leaf(lv, f, rays, q, s);
      } else {
        split<Q::kNearFirst>(lv, f, s);
      }
    }
  }

  static bool analytic(const MeshLevel<Kernel>& lv, int32_t ref) {
    return lv.analytic_leaf(lv.bvh.leaf(ref)) != kInvalidId;
  }
  static bool analytic(const InstanceLevel<Kernel>&, int32_t) { return false; }

  /// The triangles of the leaf of `f` (decoded once) against each ray of its stream.
  template <class Q>
  static void stream_leaf(const MeshLevel<Kernel>& lv, const Frame& f, std::span<const Ray> rays, Q& q,
                          Scratch& s) noexcept {
    const Leaf leaf = lv.bvh.leaf(f.ref);
    const typename Kernel::Block kb{LeafView(leaf)};
    for (uint32_t k = 0; k < f.count; ++k) {
      const uint32_t i = s.ids[f.begin + k];
      q.triangles(leaf, kb, rays, i, lv.inst, s.rays[i].tfar);
    }
  }

  /// An instance: the rays of its stream in its object space through its mesh, as a stream of
  /// their own with the answers so far.
  template <class Q>
  static void stream_leaf(const InstanceLevel<Kernel>& lv, const Frame& f, std::span<const Ray> rays, Q& q,
                          Scratch& s) noexcept {
    const uint32_t id = leaf_offset(f.ref);
    const Placed& pl = lv.placed[id];
    ObjectBatch& ob = object_batch();
    ob.rays.resize(f.count);
    for (uint32_t k = 0; k < f.count; ++k)  // an invalid one misses the instance
      ob.rays[k] = object_ray(rays[s.ids[f.begin + k]], pl.world_to_object);
    auto oq = q.object(ob, std::span<const uint32_t>(s.ids.data() + f.begin, f.count));
    trace_stream(lv.mesh(id), ob.rays, oq, scratch(1));
    q.join(oq, std::span<const uint32_t>(s.ids.data() + f.begin, f.count), s);
  }

  /// The rays of one instance's stream in its object space, and their answers.
  struct ObjectBatch {
    std::vector<Ray> rays;
    std::vector<Hit> hits;
    std::vector<uint8_t> out;
  };
  static ObjectBatch& object_batch() {
    static thread_local ObjectBatch b;
    return b;
  }

  // ---- the queries ----

  /// Closest hits into `hits` (each t: its ray's tfar, or a closer hit found already).
  struct ClosestStream {
    static constexpr bool kNearFirst = true;
    std::span<const Ray> rays;
    std::span<Hit> hits;
    static bool skip(size_t) { return false; }
    float tfar(size_t i) const { return hits[i].t; }
    /// Ray i through subtree `root` of `lv` alone; returns its search limit for the stream.
    template <class Level>
    float single(const Level& lv, size_t i, const SingleRay& sr, int32_t root) {
      ClosestSingle<Kernel> q(rays[i], hits[i]);
      trace_single<Kernel>(lv, rays[i], sr, root, q);
      return hits[i].t;
    }
    /// A leaf's triangles against ray i, lowering its stream limit `tfar` on a hit.
    RP_SIMD_INLINE void triangles(const Leaf& leaf, const typename Kernel::Block& kb, std::span<const Ray>, size_t i,
                                  uint32_t inst, float& tfar) {
      float t = hits[i].t;
      if (closest_in_block<Kernel>(leaf, kb, typename Kernel::Single(rays[i]), t, hits[i], inst)) tfar = t;
    }
    /// The query of the rays `ids` in an instance's object space: their hits so far.
    ClosestStream object(ObjectBatch& ob, std::span<const uint32_t> ids) const {
      ob.hits.resize(ids.size());
      for (size_t k = 0; k < ids.size(); ++k) ob.hits[k] = hits[ids[k]];
      return {ob.rays, ob.hits};
    }
    void join(const ClosestStream& o, std::span<const uint32_t> ids, Scratch& s) {
      for (size_t k = 0; k < ids.size(); ++k) {
        hits[ids[k]] = o.hits[k];
        s.rays[ids[k]].tfar = o.hits[k].t;
      }
    }
  };

  /// Any hits into `out` (1: occluded); a ray occluded already is left out.
  struct AnyStream {
    static constexpr bool kNearFirst = false;
    std::span<const Ray> rays;
    std::span<uint8_t> out;
    bool skip(size_t i) const { return out[i] != 0; }
    float tfar(size_t i) const { return rays[i].tfar; }
    /// Once a ray is occluded every box misses it.
    static constexpr float kDone = -std::numeric_limits<float>::infinity();
    template <class Level>
    float single(const Level& lv, size_t i, const SingleRay& sr, int32_t root) {
      if (out[i]) return kDone;
      AnySingle<Kernel> q(rays[i]);
      trace_single<Kernel>(lv, rays[i], sr, root, q);
      if (!q.found) return rays[i].tfar;
      out[i] = 1;
      return kDone;
    }
    RP_SIMD_INLINE void triangles(const Leaf& leaf, const typename Kernel::Block& kb, std::span<const Ray>, size_t i,
                                  uint32_t, float& tfar) {
      if (out[i]) return;
      if (simd::movemask(typename Kernel::Single(rays[i]).block(kb, float8(rays[i].tfar)).hit) & ((1u << leaf.n) - 1)) {
        out[i] = 1;
        tfar = kDone;
      }
    }
    AnyStream object(ObjectBatch& ob, std::span<const uint32_t> ids) const {
      ob.out.resize(ids.size());
      for (size_t k = 0; k < ids.size(); ++k) ob.out[k] = out[ids[k]];
      return {ob.rays, ob.out};
    }
    void join(const AnyStream& o, std::span<const uint32_t> ids, Scratch& s) {
      for (size_t k = 0; k < ids.size(); ++k)
        if (o.out[k] && !out[ids[k]]) {
          out[ids[k]] = 1;
          s.rays[ids[k]].tfar = kDone;
        }
    }
  };

  static void prepare(size_t n, Scratch& s) {
    if (s.rays.size() < n) s.rays.resize(n);
    if (s.ids.size() < n) s.ids.resize(n);
    s.frames.clear();
  }

  /// Enters the valid rays of `rays` that q.skip(i) does not exclude into the stream (ids
  /// [0, count), in order), ray i with q.tfar(i) (its own tfar, or its closest hit so far);
  /// a ray that needs the exact slab form (SlabRay::exact) goes to `alone(i)` instead.
  /// Returns the count. Eight rays at a time: one transpose loads them, valid_lanes decides
  /// rp::valid_ray and SlabRays8 works out their slab figures (the scalar routines' bits), so
  /// that a stream entering each instance it meets costs a few vector divisions per 8 rays.
  template <class Q, class Alone>
  static uint32_t enter_all(std::span<const Ray> rays, Scratch& s, const Q& q, Alone&& alone) noexcept {
    const size_t n = rays.size();
    uint32_t count = 0;
    const auto take = [&](size_t i, const SlabRay& slab, float tnear) {
      if (slab.exact) return alone(i);
      s.rays[i] = {slab, tnear + 0.0f, q.tfar(i)};
      s.ids[count++] = uint32_t(i);
    };
    size_t base = 0;
    for (; base + 8 <= n; base += 8) {
      float8 m[8];
      simd::load_transposed8x8(&rays[base].org.x, m);
      const Vec3x8 org{m[0], m[1], m[2]}, dir{m[4], m[5], m[6]};
      uint32_t lanes = valid_lanes(org, dir, m[3], m[7]);
      for (uint32_t b = lanes; b; b &= b - 1)
        if (q.skip(base + size_t(std::countr_zero(b)))) lanes &= ~(b & (~b + 1));
      if (!lanes) continue;
      const SlabRays8 slab(org, dir);
      for (uint32_t b = lanes; b; b &= b - 1) {
        const int l = std::countr_zero(b);
        take(base + size_t(l), slab.lane(l), rays[base + size_t(l)].tnear);
      }
    }
    for (size_t i = base; i < n; ++i)
      if (!q.skip(i) && valid_ray(rays[i])) take(i, SlabRay(rays[i]), rays[i].tnear);
    return count;
  }

  /// Tests the stream of `f` against the child boxes of its node and pushes a frame for each
  /// child some ray hits: for a query that wants the nearest answer the child its rays enter
  /// first on average on top, else in slot order. Starts loading those children.
  template <bool kNearFirst, class Level>
  static void split(const Level& lv, const Frame& f, Scratch& s) noexcept {
    const Bvh8Node& n = lv.node(f.ref);
    if (s.bits.size() < size_t(f.count) + 8) s.bits.resize(size_t(f.count) + 8);
    uint8_t* bits = s.bits.data();
    // Pass 1: each ray's hit mask, and each child's stream size.
    simd::Count8 sizes;
    float8 entries(0.0f);  // lane c: the sum of the entry distances of the rays that hit child c
    for (uint32_t k = 0; k < f.count; ++k) {
      const uint32_t i = s.ids[f.begin + k];
      float8 t_enter;
      const uint32_t b = test(n, s.rays[i], t_enter);
      if constexpr (kNearFirst) entries = entries + xsimd::select(simd::mask_from_bits(b), t_enter, float8(0.0f));
      bits[k] = uint8_t(b);
      sizes.add(b);
    }
    std::fill_n(bits + f.count, 8, uint8_t(0));
    alignas(32) uint32_t size[8];
    sizes.store(size);
    // Pass 2: child after child, its stream, by compressing 8 ids at a time. A child's stream
    // starts where the previous one ends; the up to 7 slots a compress writes past its end
    // are overwritten by the next children's streams, or lie in the 8 slots of slack.
    uint32_t at[8], end = f.top;
    for (int c = 0; c < 8; ++c) {
      at[c] = end;
      end += size[c];
    }
    if (s.ids.size() < size_t(end) + 8) s.ids.resize(size_t(end) + 8);
    const uint32_t* in = s.ids.data() + f.begin;  // ids of the stream, then at least 8 readable slots
    uint32_t hit = 0;
    for (int c = 0; c < 8; ++c) {
      if (!size[c]) continue;
      hit |= 1u << c;
      uint32_t* out = s.ids.data() + at[c];
      for (uint32_t k = 0; k < f.count; k += 8) out += simd::compress_store(in + k, simd::ByteBits8(bits + k).bit(c), out);
    }
    lv.prefetch_children(n, hit);
    int order[8], k = 0;
    for (uint32_t b = hit; b; b &= b - 1) order[k++] = std::countr_zero(b);
    if constexpr (kNearFirst) {  // by the mean entry distance of their rays: the nearest pushed last
      alignas(32) float key[8];
      entries.store_aligned(key);
      for (int c = 0; c < 8; ++c) key[c] = size[c] ? key[c] / float(size[c]) : 0.0f;
      // Insertion sort of at most 8 (std::sort's own method at this size; GCC's bounds check,
      // which cannot see k <= 8, warns about its larger-range path in the sanitizer build).
      const auto before = [&](int a, int b) { return key[a] > key[b] || (key[a] == key[b] && a < b); };
      for (int j = 1; j < k; ++j)
        for (int i = j; i > 0 && before(order[i], order[i - 1]); --i) std::swap(order[i], order[i - 1]);
    }
    for (int j = 0; j < k; ++j) s.frames.push_back({n.child[order[j]], at[order[j]], size[order[j]], end});
  }

  /// intersect_node's one-FMA form for stream ray q, with the same bits: the children hit and
  /// their entry distances.
  RP_SIMD_INLINE static uint32_t test(const Bvh8Node& n, const StreamRay& q, float8& t_enter) {
    const SlabRay& r = q.slab;
    const float* base = n.lo_x;
    const float8 inv_x(r.inv[0]), inv_y(r.inv[1]), inv_z(r.inv[2]);
    const float8 oi_x(r.oi[0]), oi_y(r.oi[1]), oi_z(r.oi[2]);
    const float8 tn_x = xsimd::fms(float8::load_aligned(base + r.near[0]), inv_x, oi_x);
    const float8 tn_y = xsimd::fms(float8::load_aligned(base + r.near[1]), inv_y, oi_y);
    const float8 tn_z = xsimd::fms(float8::load_aligned(base + r.near[2]), inv_z, oi_z);
    const float8 tf_x = xsimd::fms(float8::load_aligned(base + (24 - r.near[0])), inv_x, oi_x);
    const float8 tf_y = xsimd::fms(float8::load_aligned(base + (40 - r.near[1])), inv_y, oi_y);
    const float8 tf_z = xsimd::fms(float8::load_aligned(base + (56 - r.near[2])), inv_z, oi_z);
    return slab_hits(tn_x, tn_y, tn_z, tf_x, tf_y, tf_z, q.tnear, q.tfar, float8(r.pad), r.pad, t_enter);
  }

  const Traversal<Kernel>& t_;
};

}  // namespace rp::bvh8
