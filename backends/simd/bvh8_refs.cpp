#include "backends/simd/bvh8_refs.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <atomic>

namespace rp::bvh8::build_detail {

CornerSource::CornerSource(const Scene& scene, bool copy, const Selection& what) : scene_(scene) {
  if (!copy) return;
  const bool world = what.mesh == Selection::kWorld;
  first_ = world ? 0 : scene.mesh_base(what.mesh);
  copy_.resize(world ? scene.plane_base() : scene.meshes()[what.mesh].triangle_count());
  for (size_t m = 0; m < scene.meshes().size(); ++m) {
    if (world ? scene.is_instanced(m) : m != what.mesh) continue;  // not in this tree: never read
    const MeshView& mesh = scene.meshes()[m];
    const uint32_t base = scene.mesh_base(m) - first_;
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, mesh.triangle_count(), 4096),
                      [&](const tbb::blocked_range<uint32_t>& r) {
                        for (uint32_t t = r.begin(); t < r.end(); ++t) {
                          const Vec3f a = mesh.vertex(t, 0), b = mesh.vertex(t, 1), c = mesh.vertex(t, 2);
                          copy_[base + t] = {a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z};
                        }
                      });
  }
  if (world)
    for (uint32_t id = scene.triangle_count(); id < scene.plane_base(); ++id)
      std::fill_n(copy_[id].f, 9, std::numeric_limits<float>::quiet_NaN());
}

void CornerSource::gather(std::span<const uint32_t> ids, Vec3f* out) const {
  const size_t n = ids.size();
  if (!copy_.empty()) {
    for (size_t i = 0; i < n; ++i) {
      const float* f = copy_[ids[i] - first_].f;
      for (int j = 0; j < 3; ++j) out[3 * i + j] = {f[3 * j], f[3 * j + 1], f[3 * j + 2]};
    }
    return;
  }
  constexpr size_t kIndexAhead = 16, kCornersAhead = 8, kRing = 32;
  Triangle ring[kRing];
  for (size_t i = 0; i < std::min(n, kIndexAhead); ++i) ring[i] = triangle(ids[i]);
  const Vec3f nan(std::numeric_limits<float>::quiet_NaN());
  for (size_t i = 0; i < n; ++i) {
    if (i + kIndexAhead < n) {
      Triangle& t = ring[(i + kIndexAhead) % kRing];
      t = triangle(ids[i + kIndexAhead]);
      if (t.row) simd::prefetch(t.row);
    }
    if (i + kCornersAhead < n) {
      const Triangle& t = ring[(i + kCornersAhead) % kRing];
      if (t.row)
        for (int j = 0; j < 3; ++j) simd::prefetch(&(*t.positions)[(*t.row)[j]]);
    }
    const Triangle& t = ring[i % kRing];
    for (int j = 0; j < 3; ++j) out[3 * i + j] = t.row ? (*t.positions)[(*t.row)[j]] : nan;
  }
}

namespace {

/// What bounds() gathers of each ref, and joins across the parts of a range.
struct Bounds {
  float4 lo = simd::splat4(std::numeric_limits<float>::infinity());
  float4 hi = simd::splat4(-std::numeric_limits<float>::infinity());
  float4 clo = lo, chi = hi;
  uint32_t analytic = 0;
  void add(const PrimRef& p, uint32_t first_analytic) {
    const float4 l = load_lo(p), h = load_hi(p), c = load_center(l, h);
    lo = simd::min4(lo, l);
    hi = simd::max4(hi, h);
    clo = simd::min4(clo, c);
    chi = simd::max4(chi, c);
    analytic += p.prim_id >= first_analytic;
  }
  BoxPair boxes() const { return {to_box(lo, hi), to_box(clo, chi), analytic != 0}; }
  void join(const Bounds& o) {
    lo = simd::min4(lo, o.lo);
    hi = simd::max4(hi, o.hi);
    clo = simd::min4(clo, o.clo);
    chi = simd::max4(chi, o.chi);
    analytic += o.analytic;
  }
};

}  // namespace

BoxPair bounds(const PrimRef* base, uint32_t begin, uint32_t end, uint32_t first_analytic) {
  auto scan = [&](const tbb::blocked_range<uint32_t>& r, Bounds b) {
    for (uint32_t i = r.begin(); i < r.end(); ++i) b.add(base[i], first_analytic);
    return b;
  };
  const Bounds b = end - begin < kParallelThreshold
                       ? scan({begin, end}, Bounds{})
                       : tbb::parallel_reduce(tbb::blocked_range<uint32_t>(begin, end, kParallelThreshold), Bounds{},
                                              scan, [](Bounds a, const Bounds& o) {
                                                a.join(o);
                                                return a;
                                              });
  return b.boxes();
}

Split halves(const PrimRef* base, uint32_t begin, uint32_t end, uint32_t mid, uint32_t first_analytic) {
  return {mid, bounds(base, begin, mid, first_analytic), bounds(base, mid, end, first_analytic)};
}

size_t triangle_refs(const Scene& scene, size_t m, RefArray& refs, size_t at) {
  const MeshView& mesh = scene.meshes()[m];
  const uint32_t base = scene.mesh_base(m);
  std::atomic<size_t> degenerate{0};
  tbb::parallel_for(tbb::blocked_range<uint32_t>(0, mesh.triangle_count(), 4096),
                    [&](const tbb::blocked_range<uint32_t>& r) {
                      size_t zero_area = 0;
                      for (uint32_t t = r.begin(); t < r.end(); ++t) {
                        const Vec3f a = mesh.vertex(t, 0), b = mesh.vertex(t, 1), c = mesh.vertex(t, 2);
                        const Vec3f n = cross(b - a, c - a);
                        const bool keep = !(n.x == 0.0f && n.y == 0.0f && n.z == 0.0f);  // zero area: never hit
                        zero_area += !keep;
                        Box3f box;
                        box.extend(a);
                        box.extend(b);
                        box.extend(c);
                        refs[at + t] = PrimRef::make(box, keep ? base + t : kInvalidId);
                      }
                      degenerate += zero_area;
                    });
  return degenerate;
}

void drop_invalid(RefArray& refs) {
  refs.erase(std::remove_if(refs.begin(), refs.end(), [](const PrimRef& r) { return r.prim_id == kInvalidId; }),
             refs.end());
}

}  // namespace rp::bvh8::build_detail
