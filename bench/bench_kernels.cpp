// BM_Kernel/<slab8|moller_trumbore8|watertight8|sphere8>: the simd backend's 8-wide kernels per call, on
// seeded random inputs, with the fraction of lanes that hit as a counter. This file is built
// for AVX2+FMA; main() registers these benchmarks only when the CPU has both.

#include <benchmark/benchmark.h>

#include <random>

#include "backends/simd/packet.h"
#include "backends/simd/watertight.h"
#include "core/geometry/sphere.h"

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

/// kSets leaves of 8 random triangles (v0 in [-1, 1]^3, edges up to 0.8), as the build
/// writes them (24 distinct vertices: the costliest lookups), one after another.
std::vector<float> random_leaves() {
  const uint32_t words = leaf_words(8, kMaxLeafVertices);
  std::vector<float> out(size_t(kSets) * words + kLeafPad);
  const uint32_t ids[8] = {0, 1, 2, 3, 4, 5, 6, 7};
  for (int k = 0; k < kSets; ++k) {
    Vec3f corners[24];
    for (int l = 0; l < 8; ++l) {
      const Vec3f a = v3(-1, 1);
      corners[3 * l] = a;
      corners[3 * l + 1] = a - v3(-0.8f, 0.8f);
      corners[3 * l + 2] = a + v3(-0.8f, 0.8f);
    }
    write_leaf(out.data() + size_t(k) * words, corners, ids);
  }
  return out;
}

/// One triangle test x8: one ray against the 8 triangles of a leaf, read from the leaf as
/// traversal reads it. prepare(ray) is the per-ray set-up traversal does once per ray
/// (outside the timing); kernel(prepared, view) -> TriHit8.
template <typename Prepare, typename Kernel>
void triangle_kernel(benchmark::State& state, Prepare prepare, Kernel kernel) {
  const std::vector<float> leaves = random_leaves();
  const uint32_t words = leaf_words(8, kMaxLeafVertices);
  std::vector<decltype(prepare(Ray{}))> rays;
  for (int k = 0; k < kSets; ++k) rays.push_back(prepare(random_ray()));
  size_t hits = 0, i = 0;
  for (auto _ : state) {
    const TriHit8 h = kernel(rays[i], LeafView(Leaf(leaves.data() + i * words)));
    hits += size_t(std::popcount(simd::movemask(h.hit)));
    benchmark::DoNotOptimize(h.t);
    i = (i + 1) % kSets;
  }
  state.counters["hit_fraction"] = double(hits) / (8.0 * double(state.iterations()));
}

/// Moller-Trumbore x8, its edges from the leaf's vertices.
void BM_MollerTrumbore8(benchmark::State& state) {
  triangle_kernel(
      state, [](const Ray& r) { return r; },
      [](const Ray& r, const LeafView& tv) {
        return moller_trumbore8(Vec3x8(r.org), Vec3x8(r.dir), tv.v0, tv.e1(), tv.e2(), float8(0.0f), float8(100.0f));
      });
}

/// The watertight variant's test x8 (watertight.h): Möller–Trumbore with the bound on its edge
/// decisions, the exact test for the lanes it leaves uncertain.
void BM_Watertight8(benchmark::State& state) {
  triangle_kernel(
      state, [](const Ray& r) { return WatertightKernel::Single(r); },
      [](const WatertightKernel::Single& k, const LeafView& tv) {
        return k.block(WatertightKernel::Block(tv), float8(100.0f));
      });
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
