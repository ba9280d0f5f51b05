#include "backends/simd/bvh8_spatial.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

namespace rp::bvh8::build_detail {

namespace {

/// Position of plane k (0..nbins) of the spatial bins of `box` on `axis`.
float plane(const Box3f& box, int axis, int k, int nbins) {
  return box.lo[axis] + box.extent()[axis] * (float(k) / float(nbins));
}

/// The parts of the triangle `v` inside `box` on either side of the plane x[axis] = at,
/// each as a box (empty when there is none): the triangle's corners and the points where its
/// edges cross the plane (in double, then widened by at least two float ulps), clipped to
/// `box` and to the side. Conservative: together they cover the triangle's part inside `box`.
std::pair<Box3f, Box3f> clip(const std::array<Vec3f, 3>& v, const Box3f& box, int axis, float at) {
  Box3f left, right;
  for (int i = 0; i < 3; ++i) {
    const Vec3f &a = v[i], &b = v[(i + 1) % 3];
    if (a[axis] <= at) left.extend(a);
    if (a[axis] >= at) right.extend(a);
    if ((a[axis] < at && b[axis] > at) || (a[axis] > at && b[axis] < at)) {
      const double t = (double(at) - a[axis]) / (double(b[axis]) - a[axis]);
      Box3f cross;
      for (int c = 0; c < 3; ++c) {
        const float x = float(a[c] + t * (double(b[c]) - a[c]));
        const float e = std::abs(x) * 0x1p-22f + std::numeric_limits<float>::min();  // >= 2 ulps of x
        cross.lo[c] = c == axis ? at : x - e;
        cross.hi[c] = c == axis ? at : x + e;
      }
      left.extend(cross);
      right.extend(cross);
    }
  }
  left.hi[axis] = std::min(left.hi[axis], at);
  right.lo[axis] = std::max(right.lo[axis], at);
  auto inside = [&box](Box3f p) {
    for (int c = 0; c < 3; ++c) {
      p.lo[c] = std::max(p.lo[c], box.lo[c]);
      p.hi[c] = std::min(p.hi[c], box.hi[c]);
    }
    return p;
  };
  return {inside(left), inside(right)};
}

Box3f box_of(const PrimRef& r) { return Box3f({r.lo[0], r.lo[1], r.lo[2]}, {r.hi[0], r.hi[1], r.hi[2]}); }

int bin_of(float c, float lo, float scale, int nbins) { return std::clamp(int((c - lo) * scale), 0, nbins - 1); }

}  // namespace

float overlap(const BinnedSplit& o) {
  if (o.axis < 0) return 0.0f;  // no object split (every centroid at one point): no sides, and no boxes set
  const float4 lo = simd::max4(o.cut.left_lo, o.cut.right_lo), hi = simd::min4(o.cut.left_hi, o.cut.right_hi);
  alignas(16) float l[4], h[4];
  simd::store4(l, lo);
  simd::store4(h, hi);
  for (int c = 0; c < 3; ++c)
    if (!(l[c] <= h[c])) return 0.0f;
  return simd::area4(lo, hi);
}

BinnedSplit spatial_split(const CornerSource& corners, const RefArray& v, const Box3f& box) {
  BinnedSplit best;
  const int nbins = bins_for(uint32_t(v.size()));
  const Vec3f extent = box.extent();
  constexpr float inf = std::numeric_limits<float>::infinity();
  for (int axis = 0; axis < 3; ++axis) {
    if (!(extent[axis] > 0.0f)) continue;
    const float scale = float(nbins) / extent[axis];
    float4 lo[kBins], hi[kBins];
    uint32_t enter[kBins] = {}, leave[kBins] = {};
    std::fill_n(lo, nbins, simd::splat4(inf));
    std::fill_n(hi, nbins, simd::splat4(-inf));
    auto add = [&](int k, const Box3f& b) {
      lo[k] = simd::min4(lo[k], simd::make_float4(b.lo.x, b.lo.y, b.lo.z, 0.0f));
      hi[k] = simd::max4(hi[k], simd::make_float4(b.hi.x, b.hi.y, b.hi.z, 0.0f));
    };
    for (const PrimRef& r : v) {
      const int first = bin_of(r.lo[axis], box.lo[axis], scale, nbins);
      const int last = bin_of(r.hi[axis], box.lo[axis], scale, nbins);
      Box3f piece = box_of(r);
      if (first < last) {
        const std::array<Vec3f, 3> tri = corners(r.prim_id);
        for (int k = first; k < last; ++k) {
          const auto [l, rest] = clip(tri, piece, axis, plane(box, axis, k + 1, nbins));
          if (!l.empty()) add(k, l);
          piece = rest;
        }
      }
      if (!piece.empty()) add(last, piece);
      ++enter[first];
      ++leave[last];
    }
    const Cut c = sweep(lo, hi, enter, leave, nbins);
    if (c.sah < best.cut.sah) best = {c, axis, nbins};
  }
  return best;
}

bool divide(const CornerSource& corners, const RefArray& v, const BinnedSplit& s, const Box3f& box, RefArray& left,
            RefArray& right) {
  const int axis = s.axis;
  const int cut = s.cut.bin;
  const float scale = float(s.nbins) / box.extent()[axis], at = plane(box, axis, cut, s.nbins);
  for (const PrimRef& r : v) {
    if (bin_of(r.hi[axis], box.lo[axis], scale, s.nbins) < cut) {
      left.push_back(r);
    } else if (bin_of(r.lo[axis], box.lo[axis], scale, s.nbins) >= cut) {
      right.push_back(r);
    } else {
      const auto [l, rr] = clip(corners(r.prim_id), box_of(r), axis, at);
      if (!l.empty()) left.push_back(PrimRef::make(l, r.prim_id));
      if (!rr.empty()) right.push_back(PrimRef::make(rr, r.prim_id));
    }
  }
  return !left.empty() && !right.empty();
}

}  // namespace rp::bvh8::build_detail
