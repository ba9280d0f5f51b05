// BM_Trace/<method>/<scene>/<primary|shadow|diffuse>, BM_Build/<backend/variant>/<scene> and
// BM_Update/<backend/variant>/<scene>/<vertices|instances> (update() after motion, see BM_Update):
// every method of the available backends, named backend/variant:method as everywhere
// (e.g. BM_Trace/simd/watertight:large/bunny/primary; see methods()), plus Embree's default
// methods limited to AVX2 ("embree/default:packet8@avx2": equal SIMD width with the simd
// backend), on identical rays, traced by all threads (TBB; --threads=N or the core count);
// primary and shadow rays as coherent spans by the coherent methods, diffuse rays by the
// incoherent ones. Scenes: the embedded default and, when ../shared/scenes is present,
// bunny.obj, dragon.ply, Sponza from inside (bench/scenes/sponza-inside.json) and 16 bunnies
// placed as instances of one mesh and as 16 world meshes (bench/scenes/bunnies-*.json). Rays
// from analysis/raygen.h. BM_Pair/simd/watertight:large-vs-simd/default:large/<scene>/
// <kind> (stream for diffuse rays): the watertight variant against the default one on the same
// rays, as the median ratio of alternated traces (see BM_Pair). BM_ClosestPoints/<backend/
// variant>/<scene> and BM_ClosestPointsPair/simd/default-vs-embree/default/<scene>: closest
// points around the scene (rtcPointQuery for Embree; see BM_ClosestPoints).
//
// Before timing, each backend's hits are compared with the reference backend's (embree):
// a ray counts as a mismatch when the primitives differ and it is not a tie (both hit, t
// equal within 1e-6 relative). More than 0.001% mismatches (the 99.999% agreement floor) is
// reported with SkipWithError instead of a rate; the mismatch and tie counts are counters.

#include <benchmark/benchmark.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <random>
#include <thread>

#include "analysis/motion.h"
#include "analysis/raygen.h"
#include "analysis/reference.h"
#include "backends/registry.h"
#include "core/geometry/closest_point.h"
#include "core/queries.h"
#include "core/scene.h"
#include "io/loaders/load.h"

#ifndef RP_SOURCE_DIR
#define RP_SOURCE_DIR "."
#endif
#ifndef RP_SHARED_SCENES
#define RP_SHARED_SCENES "../shared/scenes"
#endif

namespace rp {
namespace {

struct RaySets {
  std::vector<Ray> primary, shadow, diffuse;
};

/// 1024x1024 primary rays in 4x2 packets, then shadow and diffuse rays from their hits
/// (analysis/raygen.h), the hits taken from `backend`.
RaySets make_rays(const Scene& scene, const Backend& backend) {
  const RaySet primary = primary_rays(scene, 1024, 1024);
  std::vector<Hit> hits(primary.rays.size());
  intersect_parallel(backend, primary.rays, hits, Coherence::coherent);
  return {primary.rays, shadow_rays(scene, primary, hits).rays, diffuse_rays(scene, primary, hits, 2024).rays};
}

/// A method timed here: one of the registry's (backend/variant:method, backends/registry.h),
/// or Embree's default methods on a device limited to AVX2 (the simd backend's SIMD width),
/// named with the suffix "@avx2".
struct Method {
  TraceMethod trace;
  std::string device_config;
  const std::string& name() const { return trace.name; }
  BackendOptions options() const {
    BackendOptions o = trace.options();
    o.device_config = device_config;
    return o;
  }
};

/// Every method of the registry's available backends (variants × methods), but Embree's
/// 16-wide packets only where its AVX-512 kernels run; then Embree limited to AVX2.
std::vector<Method> methods() {
  std::vector<Method> m;
  bool native16 = false;
  for (const BackendEntry& e : list_backends())
    for (const auto& [key, value] : e.facts)
      if (e.name == "embree" && key == "native_ray16") native16 = value == "yes";
  for (const TraceMethod& t : list_methods())
    if (!(t.backend == "embree" && t.method == "packet16" && !native16)) m.push_back({t, ""});
  for (const TraceMethod& t : list_methods())
    if (t.backend == "embree" && t.variant == "default" && (t.method == "packet8" || t.method == "single"))
      m.push_back({{t.name + "@avx2", t.backend, t.variant, t.method, t.coherence}, "max_isa=avx2"});
  return m;
}

/// The backend variants whose builds are timed: backend/variant, or with "@avx2" Embree's
/// default variant on a device limited to AVX2.
std::vector<Method> builds() {
  std::vector<Method> out;
  for (const Method& m : methods()) {
    Method b = m;
    b.trace.name = m.trace.backend + "/" + m.trace.variant + (m.device_config.empty() ? "" : "@avx2");
    b.trace.method.clear();
    if (std::ranges::count(out, b.trace.name, [](const Method& x) { return x.trace.name; }) == 0) out.push_back(b);
  }
  return out;
}

struct SceneFixture {
  Scene scene;
  std::unique_ptr<Backend> embree;  ///< Embree's default variant: the rays' hits, the hits compared against
  std::map<std::string, std::unique_ptr<Backend>> backends;  ///< by method name: the current benchmark's
  RaySets rays;
  std::unique_ptr<Reference> reference;
  std::map<std::string, std::vector<ReferenceHit>> reference_hits;  ///< by ray kind
};

std::map<std::string, std::string>& scene_files() {
  static std::map<std::string, std::string> files;
  return files;
}

SceneFixture& fixture(const std::string& scene_name) {
  static std::map<std::string, std::unique_ptr<SceneFixture>> cache;
  std::unique_ptr<SceneFixture>& f = cache[scene_name];
  if (!f) {
    f = std::make_unique<SceneFixture>();
    f->scene = load_scene(scene_files().at(scene_name));
    f->embree = make_backend("embree", f->scene);
    f->rays = make_rays(f->scene, *f->embree);
    f->reference = std::make_unique<Reference>(f->scene);
    for (const auto& [kind, rays] : {std::pair{"primary", &f->rays.primary}, std::pair{"shadow", &f->rays.shadow},
                                     std::pair{"diffuse", &f->rays.diffuse}}) {
      std::vector<ReferenceHit>& r = f->reference_hits[kind];
      r.resize(rays->size());
      f->reference->intersect(*rays, r);
    }
  }
  return *f;
}

/// The backends of `wanted` over the fixture's scene, built when missing; those of earlier
/// benchmarks are let go (every method's structure at once would not fit beside the large
/// scenes). Builds are not timed here.
std::vector<const Backend*> backends(SceneFixture& f, std::initializer_list<const Method*> wanted) {
  std::erase_if(f.backends, [&](const auto& entry) {
    return std::ranges::none_of(wanted, [&](const Method* m) { return m->name() == entry.first; });
  });
  std::vector<const Backend*> out;
  for (const Method* m : wanted) {
    std::unique_ptr<Backend>& b = f.backends[m->name()];
    if (!b) b = make_backend(m->trace.backend, f.scene, m->options());
    out.push_back(b.get());
  }
  return out;
}

/// Traces `rays` with all threads.
void trace(const Backend& b, const std::vector<Ray>& rays, std::vector<Hit>& hits, std::vector<uint8_t>& occ,
           bool shadow, Coherence coh) {
  if (shadow) occluded_parallel(b, rays, occ, coh);
  else intersect_parallel(b, rays, hits, coh);
}

void BM_Trace(benchmark::State& state, const Method& m, const std::string& scene_name, const std::string& kind) {
  SceneFixture& f = fixture(scene_name);
  const Backend& b = *backends(f, {&m})[0];
  const Backend& ref = *f.embree;
  const Coherence coh = m.trace.coherence;
  const std::vector<Ray>& rays = kind == "primary" ? f.rays.primary : kind == "shadow" ? f.rays.shadow : f.rays.diffuse;
  const bool shadow = kind == "shadow";
  std::vector<Hit> hits(rays.size()), ref_hits(rays.size());
  std::vector<uint8_t> occ(rays.size()), ref_occ(rays.size());
  trace(ref, rays, ref_hits, ref_occ, shadow, coh);
  trace(b, rays, hits, occ, shadow, coh);  // also the untimed warm-up
  size_t mismatch = 0, ties = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    if (shadow) {
      mismatch += occ[i] != ref_occ[i];
      continue;
    }
    if (hits[i].prim_id == ref_hits[i].prim_id) continue;
    if (hits[i].hit() && ref_hits[i].hit() && std::abs(hits[i].t - ref_hits[i].t) <= 1e-6f * ref_hits[i].t) ++ties;
    else ++mismatch;
  }
  // Accuracy against the double-precision reference on the same rays, beside Rays/s.
  const std::vector<ReferenceHit>& r = f.reference_hits.at(kind);
  size_t wrong = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    if (shadow) {
      wrong += bool(occ[i]) != r[i].hit();
      continue;
    }
    if (hits[i].hit() != r[i].hit()) ++wrong;
    else if (hits[i].hit() && hits[i].prim_id != r[i].prim_id &&
             std::abs(double(hits[i].t) - r[i].t) > 1e-6 * r[i].t)
      ++wrong;
  }
  state.counters["rays"] = double(rays.size());
  state.counters["mismatch"] = double(mismatch);
  state.counters["ties"] = double(ties);
  state.counters["ref_mismatch_rate"] = double(wrong) / std::max(1.0, double(rays.size()));
  if (double(mismatch) > 1e-5 * double(rays.size())) {
    state.SkipWithError(("hits differ from embree on " + std::to_string(mismatch) + " of " +
                         std::to_string(rays.size()) + " rays").c_str());
    return;
  }
  for (auto _ : state) {
    trace(b, rays, hits, occ, shadow, coh);
    benchmark::DoNotOptimize(hits.data());
    benchmark::DoNotOptimize(occ.data());
  }
  state.counters["Rays/s"] = benchmark::Counter(double(rays.size()) * double(state.iterations()), benchmark::Counter::kIsRate);
}

/// Each iteration of `state` runs run(0) and run(1), their order alternating; returns the
/// median over the iterations of run(0)'s speed over run(1)'s (0 without iterations).
template <class Run>
double alternated_ratio(benchmark::State& state, Run&& run) {
  std::vector<double> ratios;
  int first = 0;
  for (auto _ : state) {
    double seconds[2];
    for (int i = 0; i < 2; ++i) {
      const int k = first ^ i;
      const auto start = std::chrono::steady_clock::now();
      run(k);
      seconds[k] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    first ^= 1;
    ratios.push_back(seconds[1] / seconds[0]);
  }
  if (ratios.empty()) return 0.0;
  std::nth_element(ratios.begin(), ratios.begin() + ptrdiff_t(ratios.size() / 2), ratios.end());
  return ratios[ratios.size() / 2];
}

/// BM_Pair/<a>-vs-<b>/<scene>/<kind>: methods a and b on the same rays, each iteration one trace
/// of each (their order alternating), and as the counter `speed_ratio` the median over the
/// iterations of a's speed over b's. A shared machine slows both traces of one iteration
/// alike, so their ratio holds where the rates of separately timed benchmarks drift (measured
/// here: BM_Trace's rates move between repetitions of one run several times as much as this
/// ratio; figures: docs/notes/2026-11-29-figures-from-code-comments.md).
void BM_Pair(benchmark::State& state, const Method& a, const Method& b, const std::string& scene_name,
             const std::string& kind) {
  SceneFixture& f = fixture(scene_name);
  const std::vector<const Backend*> methods = backends(f, {&a, &b});
  const Coherence coh = a.trace.coherence;
  const std::vector<Ray>& rays = kind == "primary" ? f.rays.primary : kind == "shadow" ? f.rays.shadow : f.rays.diffuse;
  const bool shadow = kind == "shadow";
  std::vector<Hit> hits(rays.size());
  std::vector<uint8_t> occ(rays.size());
  for (const Backend* m : methods) trace(*m, rays, hits, occ, shadow, coh);  // warm-up
  state.counters["speed_ratio"] =
      alternated_ratio(state, [&](int k) { trace(*methods[size_t(k)], rays, hits, occ, shadow, coh); });
  state.counters["rays"] = double(rays.size());
}

void BM_Build(benchmark::State& state, const Method& m, const std::string& scene_name) {
  SceneFixture& f = fixture(scene_name);
  size_t bytes = 0;
  for (auto _ : state) {
    auto b = make_backend(m.trace.backend, f.scene, m.options());
    bytes = b->info().bytes;
    benchmark::DoNotOptimize(b.get());
  }
  state.counters["bytes/prim"] = double(bytes) / double(std::max<uint32_t>(1, f.scene.prim_count()));
  state.counters["prims"] = double(f.scene.prim_count());
}

/// BM_Update/<backend/variant>/<scene>/<vertices|instances>: Backend::update() after every mesh
/// of the scene is deformed, or every instance moved, by 1% of its box's diagonal
/// (analysis/motion.h; each iteration another frame of the motion from the scene at rest), with
/// the trees' work as counters. Set against BM_Build of the same variant and scene.
void BM_Update(benchmark::State& state, const Method& m, const std::string& scene_name, bool vertices) {
  const SceneFixture& f = fixture(scene_name);
  Scene moving = f.scene;
  auto b = make_backend(m.trace.backend, moving, m.options());
  UpdateReport last;
  double phase = 0.0;
  for (auto _ : state) {
    state.PauseTiming();
    phase += 0.1;
    if (vertices)
      wobble_meshes(moving, f.scene, 0.01, phase);
    else
      jostle_instances(moving, f.scene, 0.01, phase);
    state.ResumeTiming();
    last = b->update();
  }
  state.counters["refits"] = double(last.refits);
  state.counters["rebuilds"] = double(last.rebuilds);
  state.counters["top"] = double(last.top);
}

/// Points for closest-point queries: uniform in the scene's box grown by a tenth of its
/// diagonal on every side (fixed seed), and for a sample of them the distance to the surface by
/// brute force: triangles (world and placed) and planes in double, spheres' and polygons'
/// points as the scene computes them.
struct PointSet {
  std::vector<PointQuery> points;
  std::vector<double> sample_distance;  ///< of points[0 .. size)
};

const PointSet& point_set(const std::string& scene_name) {
  static std::map<std::string, PointSet> cache;
  PointSet& set = cache[scene_name];
  if (!set.points.empty()) return set;
  const Scene& s = fixture(scene_name).scene;
  const Box3f b = s.bounds();
  const Vec3f grow(0.1f * length(b.hi - b.lo));
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int i = 0; i < 100000; ++i) {
    const Vec3f lo = b.lo - grow, size = b.hi - b.lo + grow * 2.0f;
    set.points.push_back({{lo.x + u(rng) * size.x, lo.y + u(rng) * size.y, lo.z + u(rng) * size.z}});
  }
  set.sample_distance.assign(200, std::numeric_limits<double>::infinity());
  tbb::parallel_for(size_t(0), set.sample_distance.size(), [&](size_t i) {
    const Vec3d p(set.points[i].point);
    double& d = set.sample_distance[i];
    for (size_t m = 0; m < s.meshes().size(); ++m) {
      const MeshView& mesh = s.meshes()[m];
      std::vector<Affine3d> places;
      if (!s.is_instanced(m)) places.push_back(Affine3d());
      for (const Instance& in : s.instances())
        if (in.mesh == m) places.push_back(Affine3d(in.object_to_world));
      for (const Affine3d& w : places)
        for (uint32_t t = 0; t < mesh.triangle_count(); ++t) {
          const Vec3d a = w.point(Vec3d(mesh.vertex(t, 0))), bb = w.point(Vec3d(mesh.vertex(t, 1))),
                      c = w.point(Vec3d(mesh.vertex(t, 2)));
          if (zero_area(mesh.vertex(t, 0), mesh.vertex(t, 1), mesh.vertex(t, 2))) continue;
          d = std::min(d, length(closest_on_triangle(p, a, bb, c).p - p));
        }
    }
    for (uint32_t k = s.sphere_base(); k < s.plane_base(); ++k)
      if (s.locate(k).kind != PrimKind::quadric) d = std::min(d, double(s.closest_on_analytic(k, Vec3f(p)).distance));
    for (const Plane& pl : s.planes()) d = std::min(d, std::abs(dot(Vec3d(pl.normal), p) + pl.d) / length(Vec3d(pl.normal)));
  });
  return set;
}

/// Closest points of `set` with all threads.
void closest_points(const Backend& b, const PointSet& set, std::vector<ClosestPoint>& out) {
  for_each_chunk(set.points.size(), [&](size_t begin, size_t n) {
    b.closest_points(std::span(set.points).subspan(begin, n), std::span(out).subspan(begin, n));
  });
}

/// BM_ClosestPoints/<backend/variant>/<scene>: closest_points over 100,000 points around the
/// scene, with all threads, as Points/s; beside it the largest error of the distance against
/// brute force in double over a sample (max_rel_error, relative to the scene's diagonal) and
/// the points whose answer differs from Embree's default (mismatch: another distance).
void BM_ClosestPoints(benchmark::State& state, const Method& m, const std::string& scene_name) {
  SceneFixture& f = fixture(scene_name);
  if (!f.scene.quadrics().empty()) {
    state.SkipWithError("the scene has quadrics, which have no closest-point routine");
    return;
  }
  const PointSet& set = point_set(scene_name);
  const Backend& b = *backends(f, {&m})[0];
  std::vector<ClosestPoint> got(set.points.size()), ref(set.points.size());
  closest_points(*f.embree, set, ref);
  closest_points(b, set, got);  // also the warm-up
  const Box3f box = f.scene.bounds();
  const double diagonal = length(Vec3d(box.hi) - Vec3d(box.lo));
  double worst = 0;
  for (size_t i = 0; i < set.sample_distance.size(); ++i)
    worst = std::max(worst, std::abs(double(got[i].distance) - set.sample_distance[i]) / diagonal);
  size_t mismatch = 0;
  for (size_t i = 0; i < got.size(); ++i) mismatch += got[i].distance != ref[i].distance;
  state.counters["points"] = double(set.points.size());
  state.counters["max_rel_error"] = worst;
  state.counters["mismatch"] = double(mismatch);
  for (auto _ : state) {
    closest_points(b, set, got);
    benchmark::DoNotOptimize(got.data());
  }
  state.counters["Points/s"] =
      benchmark::Counter(double(set.points.size()) * double(state.iterations()), benchmark::Counter::kIsRate);
}

/// BM_ClosestPointsPair/<a>-vs-<b>/<scene>: closest points of a and b alternated on the same
/// points, as BM_Pair; `speed_ratio` is the median of a's speed over b's.
void BM_ClosestPointsPair(benchmark::State& state, const Method& a, const Method& b, const std::string& scene_name) {
  SceneFixture& f = fixture(scene_name);
  if (!f.scene.quadrics().empty()) {
    state.SkipWithError("the scene has quadrics, which have no closest-point routine");
    return;
  }
  const PointSet& set = point_set(scene_name);
  const std::vector<const Backend*> methods = backends(f, {&a, &b});
  std::vector<ClosestPoint> out(set.points.size());
  for (const Backend* m : methods) closest_points(*m, set, out);  // warm-up
  state.counters["speed_ratio"] =
      alternated_ratio(state, [&](int k) { closest_points(*methods[size_t(k)], set, out); });
  state.counters["points"] = double(set.points.size());
}

/// BM_Load/<file>: load_scene on a model of ../shared/scenes, with its triangle count and the
/// file's read rate as counters.
void BM_Load(benchmark::State& state, const std::string& path) {
  uint32_t triangles = 0;
  for (auto _ : state) {
    const Scene scene = load_scene(path);
    triangles = scene.triangle_count();
    benchmark::DoNotOptimize(triangles);
  }
  state.counters["triangles"] = double(triangles);
  state.counters["bytes/s"] = benchmark::Counter(double(std::filesystem::file_size(path)) * double(state.iterations()),
                                                 benchmark::Counter::kIsRate);
}

}  // namespace
}  // namespace rp

namespace rp::bvh8 {
void register_kernel_benchmarks();  // bench_kernels.cpp, built for AVX2+FMA
}

int main(int argc, char** argv) {
  using namespace rp;
  size_t threads = std::max(1u, std::thread::hardware_concurrency());
  std::vector<char*> args;
  for (int i = 0; i < argc; ++i) {
    const std::string a = argv[i];
    if (a.rfind("--threads=", 0) == 0) threads = size_t(std::max(1, std::atoi(a.c_str() + 10)));
    else args.push_back(argv[i]);
  }
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  benchmark::AddCustomContext("threads", std::to_string(threads));
  scene_files()["default"] = "default";
  for (const char* file : {"bunny.obj", "dragon.ply"}) {
    const std::filesystem::path p = std::filesystem::path(RP_SHARED_SCENES) / file;
    if (std::filesystem::exists(p)) scene_files()[std::filesystem::path(file).stem().string()] = p.string();
    else std::fprintf(stderr, "rp_bench: %s is absent: its benchmarks are not run\n", p.string().c_str());
  }
  // Sponza from inside (bench/scenes/sponza-inside.json: camera and lights around sponza.obj).
  if (std::filesystem::exists(std::filesystem::path(RP_SHARED_SCENES) / "sponza.obj"))
    scene_files()["sponza-inside"] = RP_SOURCE_DIR "/bench/scenes/sponza-inside.json";
  else
    std::fprintf(stderr, "rp_bench: %s/sponza.obj is absent: the sponza-inside benchmarks are not run\n", RP_SHARED_SCENES);
  // Sixteen bunnies: one mesh placed by 16 instances, and the same placements baked into
  // 16 world meshes (bench/scenes/bunnies-*.json), so the two structures meet the same rays.
  if (std::filesystem::exists(std::filesystem::path(RP_SHARED_SCENES) / "bunny.obj")) {
    scene_files()["bunnies-instanced"] = RP_SOURCE_DIR "/bench/scenes/bunnies-instanced.json";
    scene_files()["bunnies-flat"] = RP_SOURCE_DIR "/bench/scenes/bunnies-flat.json";
  }
  const auto timed = [](benchmark::internal::Benchmark* b) { b->Unit(benchmark::kMillisecond)->UseRealTime(); };
  const std::vector<Method> all = methods();
  for (const auto& [scene, path] : scene_files()) {
    (void)path;
    // Primary rays and shadow rays (towards one light, in the primary rays' tile order) are
    // coherent spans, timed with the coherent methods; diffuse bounces are not.
    for (const Method& m : all)
      for (const char* kind : {"primary", "shadow", "diffuse"})
        if ((std::string_view(kind) == "diffuse") == (m.trace.coherence == Coherence::incoherent))
          timed(benchmark::RegisterBenchmark(("BM_Trace/" + m.name() + "/" + scene + "/" + kind).c_str(), BM_Trace, m,
                                             scene, std::string(kind)));
    // Issue 19's measure: the watertight variant against the default one, each with its
    // default method for the kind's coherence.
    for (const char* kind : {"primary", "shadow", "diffuse"}) {
      const Coherence coh = std::string_view(kind) == "diffuse" ? Coherence::incoherent : Coherence::coherent;
      const auto first = [&](const char* variant) {
        return std::ranges::find_if(all, [&](const Method& m) {
          return m.trace.backend == "simd" && m.trace.variant == variant && m.trace.coherence == coh;
        });
      };
      const auto a = first("watertight"), b = first("default");
      if (a != all.end() && b != all.end())
        timed(benchmark::RegisterBenchmark(
            ("BM_Pair/" + a->name() + "-vs-" + b->name() + "/" + scene + "/" + kind).c_str(), BM_Pair, *a, *b, scene,
            std::string(kind)));
    }
    for (const Method& m : builds()) {
      timed(benchmark::RegisterBenchmark(("BM_Build/" + m.name() + "/" + scene).c_str(), BM_Build, m, scene));
      timed(benchmark::RegisterBenchmark(("BM_Update/" + m.name() + "/" + scene + "/vertices").c_str(), BM_Update, m,
                                         scene, true));
      if (scene.starts_with("bunnies-instanced"))
        timed(benchmark::RegisterBenchmark(("BM_Update/" + m.name() + "/" + scene + "/instances").c_str(), BM_Update, m,
                                           scene, false));
      timed(benchmark::RegisterBenchmark(("BM_ClosestPoints/" + m.name() + "/" + scene).c_str(), BM_ClosestPoints, m,
                                         scene));
    }
    const std::vector<Method> variants = builds();
    const auto simd = std::ranges::find(variants, std::string("simd/default"), &Method::name),
               embree = std::ranges::find(variants, std::string("embree/default"), &Method::name);
    if (simd != variants.end() && embree != variants.end())
      timed(benchmark::RegisterBenchmark(("BM_ClosestPointsPair/simd/default-vs-embree/default/" + scene).c_str(),
                                         BM_ClosestPointsPair, *simd, *embree, scene));
  }
  // The kernel benchmarks run AVX2+FMA code: only where the simd backend is offered.
  for (const BackendEntry& e : list_backends())
    if (e.name == "simd" && e.available) rp::bvh8::register_kernel_benchmarks();
  if (std::filesystem::is_directory(RP_SHARED_SCENES)) {
    std::vector<std::filesystem::path> models;
    for (const auto& e : std::filesystem::directory_iterator(RP_SHARED_SCENES))
      if (e.path().extension() == ".obj" || e.path().extension() == ".ply") models.push_back(e.path());
    std::sort(models.begin(), models.end());
    for (const auto& m : models)
      benchmark::RegisterBenchmark(("BM_Load/" + m.filename().string()).c_str(), BM_Load, m.string())
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime();
  }
  int n = int(args.size());
  benchmark::Initialize(&n, args.data());
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
