#pragma once
/// The lecture notes' median rule (SplitRule::median), which the SAH build also falls back on
/// past its depth limit. Internal to the builder (bvh8_*.cpp).

#include <cstdint>
#include <vector>

#include "backends/simd/bvh8_refs.h"

namespace rp::bvh8::build_detail {

/// The median split of a range of refs, by their primitives' centres of mass.
class MedianRule {
 public:
  /// With the median rule (o.rule), the centres of mass of the primitives of `refs`, once;
  /// `first_analytic`: prim_ids from here on are analytic primitives.
  MedianRule(const CornerSource& corners, const RefArray& refs, const BuildOptions& o, uint32_t first_analytic);

  /// The lecture notes' rule: split the longest axis of the node's box at the median centre of
  /// mass, so both halves hold the same number of primitives.
  uint32_t median_split(PrimRef* base, uint32_t begin, uint32_t end, const Box3f& box) const;

 private:
  /// A triangle's centre of mass (the lecture notes' "center of mass"), an analytic
  /// primitive's box centre, on `axis`: from mass_ with the median rule, else (the SAH
  /// build's median splits past kMaxSahDepth, rare) from the corners.
  float mass_center(const PrimRef& r, int axis) const;

  const CornerSource& corners_;
  uint32_t first_analytic_;
  std::vector<Vec3f> mass_;  ///< median rule: mass_center by prim_id - mass_base_
  uint32_t mass_base_ = 0;
};

}  // namespace rp::bvh8::build_detail
