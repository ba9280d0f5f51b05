#pragma once
/// The single-ray loop of the simd backend: one ray against the 8 children of a node at a
/// time, any level (levels.h), any query (queries.h), from any subtree, so the packet shapes
/// can hand it the rays they no longer trace together. AVX2+FMA translation units only.
///
/// For a query that wants the nearest answer (Q::kNearFirst) the children a ray hits are
/// visited near-first by their entry distance, the far ones pushed, and popped entries farther
/// than the current hit skipped; otherwise the children are pushed as they come.

#include <bit>
#include <cmath>
#include <type_traits>

#include "backends/simd/levels.h"

namespace rp::bvh8 {

/// A subtree a single ray still has to visit, with its entry distance.
struct DistanceEntry {
  int32_t ref;
  float t;
};

/// Pushes the children `bits` of node `n` onto `stack` at `sp`, sorted there by descending
/// entry distance `dist` (a stable insertion sort: ties keep the higher slot nearer the top),
/// then pops the nearest and returns its reference: near-first order for a single ray.
RP_SIMD_INLINE int32_t push_near_first(const Bvh8Node& n, uint32_t bits, const float* dist, DistanceEntry* stack,
                                       int& sp) {
  RP_DCHECK(sp + 8 <= kStackSize);
  DistanceEntry* hit = stack + sp;
  int k = 0;
  for (; bits; bits &= bits - 1) {
    const int c = std::countr_zero(bits);
    const DistanceEntry e{n.child[c], dist[c]};
    int j = k++;
    for (; j > 0 && hit[j - 1].t < e.t; --j) hit[j] = hit[j - 1];
    hit[j] = e;
  }
  sp += k - 1;
  return hit[k - 1].ref;
}

/// What the instance level sets up of a ray for its leaves: nothing.
struct NoKernelRay {
  explicit NoKernelRay(const Ray&) {}
};

template <class Kernel, class Q>
bool single_leaf(const MeshLevel<Kernel>& lv, int32_t ref, const Ray& r, const typename Kernel::Single& kr, Q& q);
template <class Kernel, class Q>
bool single_leaf(const InstanceLevel<Kernel>& lv, int32_t ref, const Ray& r, const NoKernelRay&, Q& q);

/// Valid ray `r` (set up in `sr`) through the subtree `root` of level `lv`, answering query `q`.
template <class Kernel, class Level, class Q>
void trace_single(const Level& lv, const Ray& r, const SingleRay& sr, int32_t root, Q& q) noexcept {
  // The kernel's set-up of the ray for the mesh level's leaves, once per ray (an instance's
  // leaves set up the object-space ray in its own loop).
  using KernelRay = std::conditional_t<kInstanceLevel<Level>, NoKernelRay, typename Kernel::Single>;
  const KernelRay kr(r);
  DistanceEntry stack[kStackSize];
  int sp = 0;
  int32_t ref = root;
  float tfar = q.tfar;  // in a register: only a leaf lowers it
  for (;;) {
    if (!is_leaf(ref)) {
      const Bvh8Node& n = lv.node(ref);
      float8 t_enter;
      uint32_t bits = intersect_node(n, sr, r.tnear, tfar, t_enter);
      if (bits) {
        if ((bits & (bits - 1)) == 0) {
          ref = n.child[std::countr_zero(bits)];
          continue;
        }
        if constexpr (Q::kNearFirst) {
          alignas(32) float dist[8];
          t_enter.store_aligned(dist);
          const uint32_t rest = bits & (bits - 1);
          if ((rest & (rest - 1)) == 0) {  // two children: one compare, push the far one
            const int a = std::countr_zero(bits), b = std::countr_zero(rest);
            const bool a_near = dist[a] < dist[b];  // ties: the higher slot first, as push_near_first
            const int near = a_near ? a : b, far = a_near ? b : a;
            lv.prefetch_children(n, 1u << far);
            RP_DCHECK(sp < kStackSize);
            stack[sp++] = {n.child[far], dist[far]};
            ref = n.child[near];
            continue;
          }
          lv.prefetch_children(n, bits);
          ref = push_near_first(n, bits, dist, stack, sp);
          continue;
        } else {
          RP_DCHECK(sp + 8 <= kStackSize);
          for (; bits; bits &= bits - 1) stack[sp++] = {n.child[std::countr_zero(bits)], 0.0f};
        }
      }
    } else {
      if (single_leaf(lv, ref, r, kr, q)) return;
      tfar = q.tfar;
    }
    for (;;) {  // pop, skipping subtrees entered beyond the current answer
      if (sp == 0) return;
      const DistanceEntry e = stack[--sp];
      if (!Q::kNearFirst || e.t <= std::fma(tfar, kSlabPad, sr.pad)) {  // conservative, as intersect_node
        ref = e.ref;
        break;
      }
    }
  }
}

/// A leaf of primitives against the ray; true when the query is answered.
template <class Kernel, class Q>
RP_SIMD_INLINE bool single_leaf(const MeshLevel<Kernel>& lv, int32_t ref, const Ray& r,
                                const typename Kernel::Single& kr, Q& q) {
  // The leaf's size is in its first byte, and the rows past it wait for that byte: ask for the
  // lines of a typical leaf at once (measured faster on diffuse rays; figures:
  // docs/notes/2026-11-29-figures-from-code-comments.md).
  lv.prefetch_leaf(ref);
  const Leaf leaf = lv.bvh.leaf(ref);
  if (const uint32_t id = lv.analytic_leaf(leaf); id != kInvalidId) return q.analytic(lv.scene, id, r);
  return q.triangles(leaf, typename Kernel::Block(LeafView(leaf)), kr, lv.inst);
}

/// An instance: the ray in its object space through its mesh, by the same query.
template <class Kernel, class Q>
bool single_leaf(const InstanceLevel<Kernel>& lv, int32_t ref, const Ray& r, const NoKernelRay&, Q& q) {
  const uint32_t i = leaf_offset(ref);
  const Placed& in = lv.placed[i];
  const Ray o = object_ray(r, in.world_to_object);
  if (!valid_ray(o) || in.mesh->empty()) return false;
  trace_single<Kernel>(lv.mesh(i), o, SingleRay(o), 0, q);
  return q.done();
}

}  // namespace rp::bvh8
