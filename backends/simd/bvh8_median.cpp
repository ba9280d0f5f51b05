#include "backends/simd/bvh8_median.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>

namespace rp::bvh8::build_detail {

MedianRule::MedianRule(const CornerSource& corners, const RefArray& refs, const BuildOptions& o,
                       uint32_t first_analytic)
    : corners_(corners), first_analytic_(first_analytic) {
  if (o.rule != SplitRule::median || refs.empty()) return;
  uint32_t lo = kInvalidId, hi = 0;
  for (const PrimRef& r : refs) {
    lo = std::min(lo, r.prim_id);
    hi = std::max(hi, r.prim_id);
  }
  mass_base_ = lo;
  mass_.resize(size_t(hi - lo) + 1);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, refs.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) {
      const PrimRef& ref = refs[i];
      Vec3f& c = mass_[ref.prim_id - lo];
      if (ref.prim_id >= first_analytic) {
        c = {ref.center(0), ref.center(1), ref.center(2)};
      } else {
        const std::array<Vec3f, 3> v = corners(ref.prim_id);
        c = (v[0] + v[1] + v[2]) * (1.0f / 3.0f);
      }
    }
  });
}

uint32_t MedianRule::median_split(PrimRef* base, uint32_t begin, uint32_t end, const Box3f& box) const {
  const int axis = max_abs_axis(box.extent());
  const uint32_t mid = begin + (end - begin) / 2;
  std::nth_element(base + begin, base + mid, base + end, [&](const PrimRef& a, const PrimRef& b) {
    const float ca = mass_center(a, axis), cb = mass_center(b, axis);
    return ca < cb || (ca == cb && a.prim_id < b.prim_id);
  });
  return mid;
}

float MedianRule::mass_center(const PrimRef& r, int axis) const {
  if (!mass_.empty()) return mass_[r.prim_id - mass_base_][axis];
  if (r.prim_id >= first_analytic_) return r.center(axis);
  const std::array<Vec3f, 3> v = corners_(r.prim_id);
  return ((v[0] + v[1] + v[2]) * (1.0f / 3.0f))[axis];
}

}  // namespace rp::bvh8::build_detail
