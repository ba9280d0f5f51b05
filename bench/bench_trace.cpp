// BM_Trace/<backend>/<scene>/<primary|shadow|diffuse> and BM_Build/<backend>/<scene>: every
// available backend on identical rays. Before timing, each backend's hits are compared with
// the first backend's; a backend that returns a different primitive for more than 0.01% of
// the rays (shared-edge ties allowed) is reported with SkipWithError instead of a rate.

#include <benchmark/benchmark.h>

#include <cmath>
#include <map>
#include <memory>
#include <random>

#include "backends/registry.h"
#include "engine/camera.h"
#include "engine/offset.h"
#include "engine/scene.h"

namespace rp {
namespace {

struct RaySets {
  std::vector<Ray> primary, shadow, diffuse;
};

/// Primary: pinhole over the whole image in 4x2 packets. Shadow: from each primary hit to the
/// first light. Diffuse: one cosine-distributed bounce from each primary hit (seeded).
RaySets make_rays(const Scene& scene, const Backend& backend, int width, int height) {
  RaySets rs;
  const PinholeCamera cam(scene.camera().value_or(frame_bounds(scene.bounds())), width, height);
  for (int y = 0; y < height; y += 2)
    for (int x = 0; x < width; x += 4)
      for (int lane = 0; lane < 8; ++lane) rs.primary.push_back(cam.generate(x + lane % 4 + 0.5f, y + lane / 4 + 0.5f));
  std::vector<Hit> hits(rs.primary.size());
  backend.intersect(rs.primary, hits, Coherence::coherent);
  const Box3f b = scene.bounds();
  const Vec3f light = scene.point_lights().empty() ? b.hi + b.extent() : scene.point_lights()[0].position;
  std::mt19937 rng(2024);
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  for (size_t i = 0; i < hits.size(); ++i) {
    if (!hits[i].hit()) continue;
    const SurfacePoint sp = scene.surface(rs.primary[i], hits[i]);
    const Vec3f n = dot(sp.geometric_normal, rs.primary[i].dir) < 0.0f ? sp.geometric_normal : -sp.geometric_normal;
    const Vec3f o = offset_ray_origin(sp.position, n);
    rs.shadow.push_back({o, 0.0f, light - o, 1.0f - 1e-4f});
    const float r = std::sqrt(u01(rng)), phi = 2.0f * float(kPi) * u01(rng);
    const Basis<float> tb = orthonormal_basis(n);
    const Vec3f d = tb.t * (r * std::cos(phi)) + tb.b * (r * std::sin(phi)) + n * std::sqrt(std::max(0.0f, 1.0f - r * r));
    rs.diffuse.push_back({o, 0.0f, d, std::numeric_limits<float>::infinity()});
  }
  return rs;
}

struct Fixture {
  Scene scene;
  std::map<std::string, std::unique_ptr<Backend>> backends;
  RaySets rays;
};

Fixture& default_fixture() {
  static Fixture f = [] {
    Fixture fx;
    fx.scene = make_default_scene();
    for (const std::string& name : available_backends()) fx.backends[name] = make_backend(name, fx.scene);
    fx.rays = make_rays(fx.scene, *fx.backends.begin()->second, 512, 512);
    return fx;
  }();
  return f;
}

/// Fraction of rays whose primitive differs from the reference backend's beyond a tie
/// (same t within 1e-6 relative).
double mismatch_rate(const Fixture& f, const Backend& b, const std::vector<Ray>& rays, Coherence coh) {
  const Backend& ref = *f.backends.begin()->second;
  std::vector<Hit> a(rays.size()), c(rays.size());
  ref.intersect(rays, a, coh);
  b.intersect(rays, c, coh);
  size_t bad = 0;
  for (size_t i = 0; i < rays.size(); ++i)
    if (a[i].prim_id != c[i].prim_id && !(a[i].hit() && c[i].hit() && std::abs(a[i].t - c[i].t) <= 1e-6f * a[i].t))
      ++bad;
  return rays.empty() ? 0.0 : double(bad) / double(rays.size());
}

void BM_Trace(benchmark::State& state, const std::string& backend, const std::string& kind) {
  Fixture& f = default_fixture();
  const Backend& b = *f.backends.at(backend);
  const std::vector<Ray>& rays = kind == "primary" ? f.rays.primary : kind == "shadow" ? f.rays.shadow : f.rays.diffuse;
  const Coherence coh = kind == "primary" ? Coherence::coherent : Coherence::incoherent;
  const double mismatch = mismatch_rate(f, b, rays, coh);
  if (mismatch > 1e-4) {
    state.SkipWithError(("hits differ from " + f.backends.begin()->first + " on " + std::to_string(mismatch * 100) +
                         "% of rays").c_str());
    return;
  }
  std::vector<Hit> hits(rays.size());
  std::vector<uint8_t> occ(rays.size());
  auto trace = [&] {
    if (kind == "shadow") b.occluded(rays, occ, coh);
    else b.intersect(rays, hits, coh);
  };
  trace();  // warm-up, untimed
  for (auto _ : state) {
    trace();
    benchmark::DoNotOptimize(hits.data());
    benchmark::DoNotOptimize(occ.data());
  }
  state.counters["Rays/s"] = benchmark::Counter(double(rays.size()) * double(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["mismatch"] = mismatch;
  state.counters["rays"] = double(rays.size());
}

void BM_Build(benchmark::State& state, const std::string& backend) {
  Fixture& f = default_fixture();
  size_t bytes = 0;
  for (auto _ : state) {
    auto b = make_backend(backend, f.scene);
    bytes = b->info().bytes;
    benchmark::DoNotOptimize(b.get());
  }
  state.counters["bytes/prim"] = double(bytes) / double(f.scene.prim_count());
  state.counters["prims"] = double(f.scene.prim_count());
}

const bool registered = [] {
  for (const std::string& name : available_backends()) {
    for (const char* kind : {"primary", "shadow", "diffuse"})
      benchmark::RegisterBenchmark(("BM_Trace/" + name + "/default/" + kind).c_str(), BM_Trace, name, std::string(kind))
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime();
    benchmark::RegisterBenchmark(("BM_Build/" + name + "/default").c_str(), BM_Build, name)
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime();
  }
  return true;
}();

}  // namespace
}  // namespace rp

BENCHMARK_MAIN();
