#pragma once
/// Object splits by binned SAH, and the sweep over bins that spatial splits share. Internal
/// to the builder (bvh8_*.cpp).

#include <algorithm>
#include <cstdint>
#include <limits>

#include "backends/simd/bvh8_costs.h"
#include "backends/simd/bvh8_refs.h"

namespace rp::bvh8::build_detail {

constexpr int kBins = 32;  ///< bins per axis for large nodes; small nodes use fewer (bins_for)

/// Bins for a node of n primitives: 32 near the root, where the split matters most, fewer
/// below 560 (Embree's 4 + n / 20, but at least 6), where a sweep over mostly
/// empty bins would cost more than it finds. Against 8 / 16 / 32 bins below 64 / 1024 / above:
/// a slightly faster build at about the same SAH cost (figures:
/// docs/notes/2026-11-29-figures-from-code-comments.md).
constexpr int bins_for(uint32_t n) { return n >= 560 ? kBins : std::max(6, int(4 + n / 20)); }

/// The cheapest cut of one axis's bins: cut b (1..nbins-1) leaves bins [0, b) on the left
/// and [b, nbins) on the right; its cost is the sum over both sides of box area times refs,
/// a ref counted left of every cut after its entry bin and right of every cut up to its
/// exit bin (the same bin for object splits). sah = inf when no cut has refs on both sides.
struct Cut {
  float sah = std::numeric_limits<float>::infinity();
  int bin = 0;
  float4 left_lo, left_hi, right_lo, right_hi;
};
/// The best cut over three axes of nbins bins each (object or spatial): axis -1 when none.
struct BinnedSplit {
  Cut cut;
  int axis = -1, nbins = 0;
};

/// The cheapest cut of one axis's bins (see Cut).
Cut sweep(const float4* lo, const float4* hi, const uint32_t* enter, const uint32_t* leave, int nbins);

/// Binned SAH (Wald, "On fast Construction of SAH-based Bounding Volume Hierarchies", 2007):
/// 8-32 bins per axis over the centroid bounds.
BinnedSplit object_split(const PrimRef* base, uint32_t begin, uint32_t end, const Box3f& centroids);

/// Whether a leaf of n refs costs no more than a split of this SAH sum under `box`.
inline bool leaf_cheaper(uint32_t n, float sah, const Box3f& box) {
  const float area = box.area();
  const float split_cost =
      area > 0.0f ? kTraversalCost + kIntersectionCost * sah / area : std::numeric_limits<float>::infinity();
  return kIntersectionCost * float(n) <= split_cost;
}

/// Moves refs[begin, end) to the sides of `o` (or halves them where it has no cut, or where
/// it would leave a side empty). `first_analytic`: prim_ids from here on are analytic
/// primitives.
Split apply(PrimRef* base, uint32_t begin, uint32_t end, const BinnedSplit& o, const Box3f& centroids,
            uint32_t first_analytic);

}  // namespace rp::bvh8::build_detail
