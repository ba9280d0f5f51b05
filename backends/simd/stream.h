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
/// a leaf holding an analytic primitive, go on ray by ray (Traversal::closest / any, from
/// that node).
///
/// In a scene with instances the batch then goes down the instance tree (instances.h) as a
/// stream the same way; at an instance, the rays of its stream are mapped into its object
/// space (rp::object_ray, the single-ray path's bits) and traced through the mesh's tree as a
/// stream of their own, with the hits found so far (the map keeps t the world t).
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
/// triangle test, and hits resolved by the rule of Traversal (the least (t, prim_id)), which
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
  explicit StreamTraversal(const Traversal<Kernel>& t) : t_(t), bvh_(t.bvh()) {}

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
  /// A thread's buffers: level 0 for the world's tree and the instance tree, level 1 for an
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
    closest_tree(rays, hits, scratch(0), kNoInstance);
    if (const InstanceQueries<Kernel>* in = t_.instances()) closest_instances(*in, rays, hits);
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
    any_tree(rays, out, scratch(0));
    if (const InstanceQueries<Kernel>* in = t_.instances()) any_instances(*in, rays, out);
  }

  /// Closest hits in this traversal's tree of the valid rays of `rays` into `hits` (each t:
  /// its ray's tfar, or a closer hit found already), naming instance `inst`.
  void closest_tree(std::span<const Ray> rays, std::span<Hit> hits, Scratch& s, uint32_t inst) const noexcept {
    if (bvh_.empty()) return;
    const size_t n = rays.size();
    prepare(n, s);
    const uint32_t count = enter_all(
        rays, s, [](size_t) { return false; }, [&](size_t i) { return hits[i].t; },
        [&](size_t i) { t_.closest(rays[i], 0, hits[i], inst); });
    traverse<false>(
        bvh_.nodes.data(), false, count, s, [&](const Frame& f) { leaf_closest(f, s, rays, hits, inst); },
        [&](uint32_t i, int32_t ref) {
          t_.closest(rays[i], SingleRay(rays[i], s.rays[i].slab), ref, hits[i], inst);
          s.rays[i].tfar = hits[i].t;
        });
  }

  /// Any hits in this traversal's tree of the valid rays of `rays` not occluded already
  /// (out[i] == 0), into `out`.
  void any_tree(std::span<const Ray> rays, std::span<uint8_t> out, Scratch& s) const noexcept {
    if (bvh_.empty()) return;
    const size_t n = rays.size();
    prepare(n, s);
    const uint32_t count = enter_all(
        rays, s, [&](size_t i) { return out[i] != 0; }, [&](size_t i) { return rays[i].tfar; },
        [&](size_t i) { out[i] = t_.any(rays[i], 0); });
    const auto done = [&](uint32_t i) {
      out[i] = 1;
      s.rays[i].tfar = -std::numeric_limits<float>::infinity();  // every box misses from now on
    };
    traverse<true>(
        bvh_.nodes.data(), false, count, s, [&](const Frame& f) { leaf_any(f, s, rays, out, done); },
        [&](uint32_t i, int32_t ref) {
          if (!out[i] && t_.any(rays[i], SingleRay(rays[i], s.rays[i].slab), ref)) done(i);
        });
  }

  // ---- the instance level ----

  /// The rays of one instance's stream in its object space, and their hits.
  struct ObjectBatch {
    std::vector<Ray> rays;
    std::vector<Hit> hits;
    std::vector<uint8_t> out;
  };
  static ObjectBatch& object_batch() {
    static thread_local ObjectBatch b;
    return b;
  }

  /// The valid rays of `rays` (not those `skip` marks, when given) as one stream down the
  /// instance tree, ray i with tfar_of(i): a ray that needs the exact slab form goes through
  /// the instance level by itself (`alone(i)`); `at_instance(f)` takes an instance's stream,
  /// `alone_from(i, ref)` ray i from node ref.
  template <bool kAny, class TfarOf, class AtInstance, class Alone, class AloneFrom>
  void instance_streams(const InstanceQueries<Kernel>& in, std::span<const Ray> rays, TfarOf&& tfar_of,
                        const uint8_t* skip, AtInstance&& at_instance, Alone&& alone,
                        AloneFrom&& alone_from) const noexcept {
    const InstanceTree& tree = in.tree();
    if (tree.empty()) return;
    Scratch& s = scratch(0);
    const size_t n = rays.size();
    prepare(n, s);
    const uint32_t count = enter_all(
        rays, s, [&](size_t i) { return skip && skip[i]; }, tfar_of, [&](size_t i) { alone(uint32_t(i)); });
    traverse<kAny>(tree.nodes.data(), true, count, s, at_instance, alone_from);
  }

  /// Closest hits among the instances of the valid rays of `rays`, into `hits`.
  void closest_instances(const InstanceQueries<Kernel>& in, std::span<const Ray> rays,
                         std::span<Hit> hits) const noexcept {
    Scratch& s = scratch(0);
    ObjectBatch& ob = object_batch();
    const auto at_instance = [&](const Frame& f) {
      const uint32_t id = leaf_offset(f.ref);
      const typename InstanceQueries<Kernel>::Placed& pl = in.placed(id);
      ob.rays.resize(f.count);
      ob.hits.resize(f.count);
      for (uint32_t k = 0; k < f.count; ++k) {
        const uint32_t i = s.ids[f.begin + k];
        ob.rays[k] = object_ray(rays[i], pl.world_to_object);  // an invalid one misses the instance
        ob.hits[k] = hits[i];
      }
      StreamTraversal(*pl.mesh).closest_tree(ob.rays, ob.hits, scratch(1), id);
      for (uint32_t k = 0; k < f.count; ++k) {
        const uint32_t i = s.ids[f.begin + k];
        hits[i] = ob.hits[k];
        s.rays[i].tfar = hits[i].t;
      }
    };
    instance_streams<false>(
        in, rays, [&](size_t i) { return hits[i].t; }, nullptr, at_instance,
        [&](uint32_t i) { in.closest(rays[i], hits[i]); },
        [&](uint32_t i, int32_t ref) {
          in.closest(rays[i], SingleRay(rays[i], s.rays[i].slab), ref, hits[i]);
          s.rays[i].tfar = hits[i].t;
        });
  }

  /// Any hits among the instances of the valid rays of `rays` not occluded already, into `out`.
  void any_instances(const InstanceQueries<Kernel>& in, std::span<const Ray> rays,
                     std::span<uint8_t> out) const noexcept {
    Scratch& s = scratch(0);
    ObjectBatch& ob = object_batch();
    const auto done = [&](uint32_t i) {
      out[i] = 1;
      s.rays[i].tfar = -std::numeric_limits<float>::infinity();
    };
    const auto at_instance = [&](const Frame& f) {
      const typename InstanceQueries<Kernel>::Placed& pl = in.placed(leaf_offset(f.ref));
      ob.rays.resize(f.count);
      ob.out.assign(f.count, 0);
      for (uint32_t k = 0; k < f.count; ++k) {
        const uint32_t i = s.ids[f.begin + k];
        ob.rays[k] = object_ray(rays[i], pl.world_to_object);
        ob.out[k] = out[i];
      }
      StreamTraversal(*pl.mesh).any_tree(ob.rays, ob.out, scratch(1));
      for (uint32_t k = 0; k < f.count; ++k)
        if (ob.out[k] && !out[s.ids[f.begin + k]]) done(s.ids[f.begin + k]);
    };
    instance_streams<true>(
        in, rays, [&](size_t i) { return rays[i].tfar; }, out.data(), at_instance,
        [&](uint32_t i) { out[i] = in.any(rays[i]); },
        [&](uint32_t i, int32_t ref) {
          if (!out[i] && in.any(rays[i], SingleRay(rays[i], s.rays[i].slab), ref)) done(i);
        });
  }

  static void prepare(size_t n, Scratch& s) {
    if (s.rays.size() < n) s.rays.resize(n);
    if (s.ids.size() < n) s.ids.resize(n);
    s.frames.clear();
  }

  /// Enters the valid rays of `rays` that `skip(i)` does not exclude into the stream (ids
  /// [0, count), in order), ray i with tfar_of(i) (its own tfar, or its closest hit so far);
  /// a ray that needs the exact slab form (SlabRay::exact) goes to `alone(i)` instead.
  /// Returns the count. Eight rays at a time: one transpose loads them, valid_lanes decides
  /// rp::valid_ray and SlabRays8 works out their slab figures (the scalar routines' bits), so
  /// that a stream entering each instance it meets costs a few vector divisions per 8 rays.
  template <class Skip, class TfarOf, class Alone>
  static uint32_t enter_all(std::span<const Ray> rays, Scratch& s, Skip&& skip, TfarOf&& tfar_of,
                            Alone&& alone) noexcept {
    const size_t n = rays.size();
    uint32_t count = 0;
    const auto take = [&](size_t i, const SlabRay& slab, float tnear) {
      if (slab.exact) return alone(i);
      s.rays[i] = {slab, tnear + 0.0f, tfar_of(i)};
      s.ids[count++] = uint32_t(i);
    };
    size_t base = 0;
    for (; base + 8 <= n; base += 8) {
      float8 m[8];
      simd::load_transposed8x8(&rays[base].org.x, m);
      const Vec3x8 org{m[0], m[1], m[2]}, dir{m[4], m[5], m[6]};
      uint32_t lanes = valid_lanes(org, dir, m[3], m[7]);
      for (uint32_t b = lanes; b; b &= b - 1)
        if (skip(base + size_t(std::countr_zero(b)))) lanes &= ~(b & (~b + 1));
      if (!lanes) continue;
      const SlabRays8 slab(org, dir);
      for (uint32_t b = lanes; b; b &= b - 1) {
        const int l = std::countr_zero(b);
        take(base + size_t(l), slab.lane(l), rays[base + size_t(l)].tnear);
      }
    }
    for (size_t i = base; i < n; ++i)
      if (!skip(i) && valid_ray(rays[i])) take(i, SlabRay(rays[i]), rays[i].tnear);
    return count;
  }

  /// The traversal loop shared by both queries and both levels, over the tree of `nodes`
  /// (this traversal's, or the instance tree when `instances`): `leaf(frame)` takes a leaf's
  /// (or an instance's) stream, `alone(i, ref)` takes ray i through subtree ref by itself.
  template <bool kAny, class LeafFn, class AloneFn>
  void traverse(const Bvh8Node* nodes, bool instances, uint32_t count, Scratch& s, LeafFn&& leaf,
                AloneFn&& alone) const noexcept {
    if (count) s.frames.push_back({0, 0, count, count});
    while (!s.frames.empty()) {
      const Frame f = s.frames.back();
      s.frames.pop_back();
      if (f.count < kMinStream || (!instances && is_leaf(f.ref) && t_.analytic_leaf(bvh_.leaf(f.ref)) != kInvalidId)) {
        for (uint32_t k = 0; k < f.count; ++k) alone(s.ids[f.begin + k], f.ref);
      } else if (is_leaf(f.ref)) {
        leaf(f);
      } else {
        split<kAny>(nodes, instances, f, s);
      }
    }
  }

  /// Tests the stream of `f` against the child boxes of its node and pushes a frame for each
  /// child some ray hits: for closest hits the child its rays enter first on average on top,
  /// for any hits in slot order. Starts loading those children.
  template <bool kAny>
  void split(const Bvh8Node* nodes, bool instances, const Frame& f, Scratch& s) const noexcept {
    const Bvh8Node& n = nodes[size_t(f.ref)];
    if (s.bits.size() < size_t(f.count) + 8) s.bits.resize(size_t(f.count) + 8);
    uint8_t* bits = s.bits.data();
    // Pass 1: each ray's hit mask, and each child's stream size.
    simd::Count8 sizes;
    float8 entries(0.0f);  // lane c: the sum of the entry distances of the rays that hit child c
    for (uint32_t k = 0; k < f.count; ++k) {
      const uint32_t i = s.ids[f.begin + k];
      float8 t_enter;
      const uint32_t b = test(n, s.rays[i], t_enter);
      if constexpr (!kAny) entries = entries + xsimd::select(simd::mask_from_bits(b), t_enter, float8(0.0f));
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
    if (instances) {  // instance tree nodes (an instance leaf has no data here)
      for (uint32_t b = hit; b; b &= b - 1)
        if (const int32_t c = n.child[std::countr_zero(b)]; !is_leaf(c))
          for (uint32_t off = 0; off < sizeof(Bvh8Node); off += 64)
            simd::prefetch(reinterpret_cast<const char*>(&nodes[size_t(c)]) + off);
    } else {
      t_.prefetch_children(n, hit);
    }
    int order[8], k = 0;
    for (uint32_t b = hit; b; b &= b - 1) order[k++] = std::countr_zero(b);
    if constexpr (!kAny) {  // by the mean entry distance of their rays: the nearest pushed last
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

  /// The triangles of the leaf of `f` (decoded once) against each ray of its stream.
  void leaf_closest(const Frame& f, Scratch& s, std::span<const Ray> rays, std::span<Hit> hits,
                    uint32_t inst) const noexcept {
    const Leaf leaf = bvh_.leaf(f.ref);
    const typename Kernel::Block kb{LeafView(leaf)};
    for (uint32_t k = 0; k < f.count; ++k) {
      const uint32_t i = s.ids[f.begin + k];
      float tfar = hits[i].t;
      if (Traversal<Kernel>::leaf_single(leaf, kb, typename Kernel::Single(rays[i]), tfar, hits[i], inst))
        s.rays[i].tfar = tfar;
    }
  }

  /// The same for any hits: `done(i)` for each ray a triangle occludes.
  template <class Done>
  void leaf_any(const Frame& f, Scratch& s, std::span<const Ray> rays, std::span<const uint8_t> out,
                Done&& done) const noexcept {
    const Leaf leaf = bvh_.leaf(f.ref);
    const typename Kernel::Block kb{LeafView(leaf)};
    const uint32_t slots = (1u << leaf.n) - 1;
    for (uint32_t k = 0; k < f.count; ++k) {
      const uint32_t i = s.ids[f.begin + k];
      if (out[i]) continue;
      if (simd::movemask(typename Kernel::Single(rays[i]).block(kb, float8(rays[i].tfar)).hit) & slots) done(i);
    }
  }

  const Traversal<Kernel>& t_;
  const Bvh8& bvh_;
};

}  // namespace rp::bvh8
