#include "backends/simd/bvh8_binned_sah.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

namespace rp::bvh8::build_detail {

namespace {

using simd::int4;

/// A node's bin mapping on the three axes at once: lane a of (*this)(centre) is a ref's bin
/// on axis a, clamp(int((centre - lo) * nbins / extent), 0, nbins - 1), the one rule of
/// the binning and the partition (0 on an axis of zero extent).
struct BinMap {
  float4 origin, scale;
  int4 top;
  BinMap(const Box3f& centroids, int nbins) {
    const Vec3f extent = centroids.extent();
    const float nb = float(nbins);
    origin = simd::make_float4(centroids.lo.x, centroids.lo.y, centroids.lo.z, 0.0f);
    scale = simd::make_float4(extent.x > 0.0f ? nb / extent.x : 0.0f, extent.y > 0.0f ? nb / extent.y : 0.0f,
                              extent.z > 0.0f ? nb / extent.z : 0.0f, 0.0f);
    top = simd::splat4(nbins - 1);
  }
  int4 operator()(float4 center) const {
    return simd::min4(simd::max4(simd::truncate4((center - origin) * scale), simd::splat4(0)), top);
  }
};

/// Moves the refs whose bin on the split's axis lies below its cut before the others and
/// returns the split: each side's box is the cut's, each side's centroid bounds and
/// analytic flag are gathered on the way (no second scan). Lomuto's scheme with the swap
/// made whether or not the ref goes left, so which side a ref takes is data, not a branch:
/// the two-pointer scheme this replaced guessed wrong about once per ref, and the guesses
/// were a large part of its time (figures: docs/notes/2026-11-29-figures-from-code-comments.md).
Split partition(PrimRef* base, uint32_t begin, uint32_t end, const BinnedSplit& o, const BinMap& map,
                uint32_t first_analytic) {
  const float4 inf = simd::splat4(std::numeric_limits<float>::infinity());
  const float4 ninf = simd::splat4(-std::numeric_limits<float>::infinity());
  float4 left_lo = inf, left_hi = ninf, right_lo = inf, right_hi = ninf;
  uint32_t left_analytic = 0, right_analytic = 0;
  PrimRef* j = base + begin;
  for (PrimRef* i = base + begin; i != base + end; ++i) {
    const PrimRef x = *i;
    const float4 c = load_center(load_lo(x), load_hi(x));
    alignas(16) int32_t k[4];
    simd::store4(k, map(c));
    const bool left = k[o.axis] < o.cut.bin;
    *i = *j;  // [base + begin, j) went left, [j, i) right
    *j = x;
    j += left;
    const float4 m = simd::mask4(left);
    left_lo = simd::min4(left_lo, simd::select4(m, c, inf));
    left_hi = simd::max4(left_hi, simd::select4(m, c, ninf));
    right_lo = simd::min4(right_lo, simd::select4(m, inf, c));
    right_hi = simd::max4(right_hi, simd::select4(m, ninf, c));
    const uint32_t analytic = x.prim_id >= first_analytic;
    left_analytic += analytic & left;
    right_analytic += analytic & !left;
  }
  return {uint32_t(j - base),
          {to_box(o.cut.left_lo, o.cut.left_hi), to_box(left_lo, left_hi), left_analytic != 0},
          {to_box(o.cut.right_lo, o.cut.right_hi), to_box(right_lo, right_hi), right_analytic != 0}};
}

/// Bin boxes and counts for all three axes in one pass over the refs: the three bin indices
/// of a centroid in one 4-wide step, each bin box a 4-wide min/max (in parallel for large
/// ranges; unions and integer sums are exact, so the bins do not depend on the cut either).
struct Bins {
  float4 lo[3][kBins], hi[3][kBins];
  uint32_t count[3][kBins];
  int nbins;
  explicit Bins(int n) : nbins(n) {
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < n; ++b) {
        lo[a][b] = simd::splat4(std::numeric_limits<float>::infinity());
        hi[a][b] = simd::splat4(-std::numeric_limits<float>::infinity());
        count[a][b] = 0;
      }
  }
  void join(const Bins& o) {
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < nbins; ++b) {
        lo[a][b] = simd::min4(lo[a][b], o.lo[a][b]);
        hi[a][b] = simd::max4(hi[a][b], o.hi[a][b]);
        count[a][b] += o.count[a][b];
      }
  }
};
/// Fills `out` (constructed for nbins): a return by value would copy its 3.5 KB per node.
void bin(const PrimRef* base, uint32_t begin, uint32_t end, const BinMap& map, Bins& out) {
  auto scan_into = [&](const tbb::blocked_range<uint32_t>& r, Bins& b) {
    for (uint32_t i = r.begin(); i < r.end(); ++i) {
      const PrimRef& p = base[i];
      const float4 lo = load_lo(p), hi = load_hi(p);
      alignas(16) int32_t k[4];
      simd::store4(k, map(load_center(lo, hi)));
      for (int a = 0; a < 3; ++a) {
        b.lo[a][k[a]] = simd::min4(b.lo[a][k[a]], lo);
        b.hi[a][k[a]] = simd::max4(b.hi[a][k[a]], hi);
        ++b.count[a][k[a]];
      }
    }
  };
  if (end - begin < kParallelThreshold) {  // most nodes: no copies of the bins
    scan_into({begin, end}, out);
    return;
  }
  auto scan = [&](const tbb::blocked_range<uint32_t>& r, Bins b) {
    scan_into(r, b);
    return b;
  };
  out = tbb::parallel_reduce(tbb::blocked_range<uint32_t>(begin, end, kParallelThreshold), Bins(out.nbins), scan,
                             [](Bins a, const Bins& b) {
                               a.join(b);
                               return a;
                             });
}

static uint32_t object_median(uint32_t begin, uint32_t end) { return begin + (end - begin) / 2; }

}  // namespace

Cut sweep(const float4* lo, const float4* hi, const uint32_t* enter, const uint32_t* leave, int nbins) {
  constexpr float inf = std::numeric_limits<float>::infinity();
  float4 right_lo[kBins], right_hi[kBins];
  float right_area[kBins];
  uint32_t right_count[kBins];
  float4 l = simd::splat4(inf), h = simd::splat4(-inf);
  uint32_t count = 0;
  for (int b = nbins - 1; b > 0; --b) {  // a box with no refs yet is never priced (count 0)
    right_lo[b] = l = simd::min4(l, lo[b]);
    right_hi[b] = h = simd::max4(h, hi[b]);
    count += leave[b];
    right_area[b] = simd::area4(l, h);
    right_count[b] = count;
  }
  l = simd::splat4(inf);
  h = simd::splat4(-inf);
  count = 0;
  Cut best;
  for (int b = 1; b < nbins; ++b) {
    l = simd::min4(l, lo[b - 1]);
    h = simd::max4(h, hi[b - 1]);
    count += enter[b - 1];
    if (count == 0 || right_count[b] == 0) continue;
    const float cost = simd::area4(l, h) * float(count) + right_area[b] * float(right_count[b]);
    if (cost < best.sah) best = {cost, b, l, h, right_lo[b], right_hi[b]};
  }
  return best;
}

BinnedSplit object_split(const PrimRef* base, uint32_t begin, uint32_t end, const Box3f& centroids) {
  const Vec3f extent = centroids.extent();
  BinnedSplit best;
  const int nbins = bins_for(end - begin);
  Bins bins(nbins);
  bin(base, begin, end, BinMap(centroids, nbins), bins);
  for (int axis = 0; axis < 3; ++axis) {
    if (!(extent[axis] > 0.0f)) continue;
    const Cut c = sweep(bins.lo[axis], bins.hi[axis], bins.count[axis], bins.count[axis], nbins);
    if (c.sah < best.cut.sah) best = {c, axis, nbins};
  }
  return best;
}

Split apply(PrimRef* base, uint32_t begin, uint32_t end, const BinnedSplit& o, const Box3f& centroids,
            uint32_t first_analytic) {
  if (o.axis < 0)
    return halves(base, begin, end, object_median(begin, end), first_analytic);  // every centroid coincides
  const Split s = partition(base, begin, end, o, BinMap(centroids, o.nbins), first_analytic);
  return (s.mid == begin || s.mid == end) ? halves(base, begin, end, object_median(begin, end), first_analytic) : s;
}

}  // namespace rp::bvh8::build_detail
