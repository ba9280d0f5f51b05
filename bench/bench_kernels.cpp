// BM_Kernel/<slab8|moller_trumbore8|sphere8>: the simd backend's 8-wide kernels per call, on
// seeded random inputs, with the fraction of lanes that hit as a counter. This file is built
// for AVX2+FMA; main() registers these benchmarks only when the CPU has both.

#include <benchmark/benchmark.h>

#include <random>

#include "backends/simd/kernels.h"
#include "engine/geometry/sphere.h"

namespace rp::bvh8 {

void register_kernel_benchmarks();

namespace {

constexpr int kSets = 1024;  ///< distinct inputs cycled through, so the branch predictor cannot learn one

std::mt19937& rng() {
  static std::mt19937 r(99);
  return r;
}
float u(float lo, float hi) { return std::uniform_real_distribution<float>(lo, hi)(rng()); }
Vec3f v3(float lo, float hi) { return {u(lo, hi), u(lo, hi), u(lo, hi)}; }

Ray random_ray() { return {v3(-2, 2), 0.0f, normalize(v3(-1, 1)), 100.0f}; }

/// Slab test x8: one ray against the 8 child boxes of a node.
void BM_Slab8(benchmark::State& state) {
  std::vector<Bvh8Node> nodes(kSets);
  std::vector<Ray> rays(kSets);
  for (int s = 0; s < kSets; ++s) {
    for (int c = 0; c < 8; ++c) {
      const Vec3f a = v3(-1, 1), b = a + v3(0, 0.5f);
      nodes[s].lo_x[c] = a.x; nodes[s].lo_y[c] = a.y; nodes[s].lo_z[c] = a.z;
      nodes[s].hi_x[c] = b.x; nodes[s].hi_y[c] = b.y; nodes[s].hi_z[c] = b.z;
      nodes[s].child[c] = c;
    }
    rays[s] = random_ray();
  }
  std::vector<SingleRay> prepared;
  for (const Ray& r : rays) prepared.emplace_back(r);
  size_t hits = 0, i = 0;
  for (auto _ : state) {
    float8 t;
    const uint32_t m = intersect_node(nodes[i], prepared[i], 0.0f, 100.0f, t);
    hits += size_t(std::popcount(m));
    benchmark::DoNotOptimize(t);
    i = (i + 1) % kSets;
  }
  state.counters["hit_fraction"] = double(hits) / (8.0 * double(state.iterations()));
}

/// kSets blocks of 8 random triangles (v0 in [-1, 1]^3, edges up to 0.8) in `layout`.
std::vector<Tri8> random_blocks(TriangleLayout layout) {
  std::vector<Tri8> blocks(kSets);
  for (Tri8& b : blocks)
    for (int l = 0; l < 8; ++l) {
      const Vec3f a = v3(-1, 1), e1 = v3(-0.8f, 0.8f), e2 = v3(-0.8f, 0.8f);
      const Vec3f p1 = layout == TriangleLayout::edges ? e1 : a - e1, p2 = layout == TriangleLayout::edges ? e2 : a + e2;
      b.v0_x[l] = a.x; b.v0_y[l] = a.y; b.v0_z[l] = a.z;
      b.p1_x[l] = p1.x; b.p1_y[l] = p1.y; b.p1_z[l] = p1.z;
      b.p2_x[l] = p2.x; b.p2_y[l] = p2.y; b.p2_z[l] = p2.z;
    }
  return blocks;
}

/// One triangle test x8: one ray against the 8 triangles of a block. prepare(ray) is the
/// per-ray set-up traversal does once per ray (outside the timing); kernel(prepared, block) -> TriHit8.
template <typename Prepare, typename Kernel>
void triangle_kernel(benchmark::State& state, TriangleLayout layout, Prepare prepare, Kernel kernel) {
  const std::vector<Tri8> blocks = random_blocks(layout);
  std::vector<decltype(prepare(Ray{}))> rays;
  for (int k = 0; k < kSets; ++k) rays.push_back(prepare(random_ray()));
  size_t hits = 0, i = 0;
  for (auto _ : state) {
    const TriHit8 h = kernel(rays[i], LeafView(blocks[i]));
    hits += size_t(std::popcount(simd::movemask(h.hit)));
    benchmark::DoNotOptimize(h.t);
    i = (i + 1) % kSets;
  }
  state.counters["hit_fraction"] = double(hits) / (8.0 * double(state.iterations()));
}

/// Moller-Trumbore x8 (edge layout).
void BM_MollerTrumbore8(benchmark::State& state) {
  triangle_kernel(
      state, TriangleLayout::edges, [](const Ray& r) { return r; },
      [](const Ray& r, const LeafView& tv) {
        return moller_trumbore8(Vec3x8(r.org), Vec3x8(r.dir), tv.v0, tv.p1, tv.p2, float8(0.0f), float8(100.0f));
      });
}

/// Watertight x8 (vertex layout), the per-ray shear and axis permutation prepared once per ray.
void BM_Watertight8(benchmark::State& state) {
  triangle_kernel(
      state, TriangleLayout::vertices, [](const Ray& r) { return WatertightRays(&r, 1); },
      [](const WatertightRays& w, const LeafView& tv) { return watertight8(w, tv.v0, tv.p1, tv.p2, float8(100.0f)); });
}

/// Sphere x8: one ray against 8 spheres by the scalar stable-quadratic routine the backends
/// share (the simd backend tests analytic primitives with the scalar routines).
void BM_Sphere8(benchmark::State& state) {
  struct S { Vec3f c; float r; };
  std::vector<std::array<S, 8>> spheres(kSets);
  std::vector<Ray> rays(kSets);
  for (int s = 0; s < kSets; ++s) {
    for (S& sp : spheres[s]) sp = {v3(-1, 1), u(0.1f, 0.6f)};
    rays[s] = random_ray();
  }
  size_t hits = 0, i = 0;
  for (auto _ : state) {
    for (const S& sp : spheres[i]) {
      const Intersection<float> h = intersect_sphere_algebraic(rays[i], sp.c, sp.r);
      hits += h.hit;
      benchmark::DoNotOptimize(h.t);
    }
    i = (i + 1) % kSets;
  }
  state.counters["hit_fraction"] = double(hits) / (8.0 * double(state.iterations()));
}

}  // namespace

void register_kernel_benchmarks() {
  benchmark::RegisterBenchmark("BM_Kernel/slab8", BM_Slab8);
  benchmark::RegisterBenchmark("BM_Kernel/moller_trumbore8", BM_MollerTrumbore8);
  benchmark::RegisterBenchmark("BM_Kernel/watertight8", BM_Watertight8);
  benchmark::RegisterBenchmark("BM_Kernel/sphere8", BM_Sphere8);
}

}  // namespace rp::bvh8
