// The guarantees `raypack stability` measures, asserted: the watertight variant never leaks
// through a closed mesh at any tested translation or scale; no method reports a hit for a
// NaN/Inf ray or outside [tnear, tfar]; offset secondary rays never hit the surface they leave.
// Plus the properties of the families themselves (seeded, sized as asked, effective).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>

#include "analysis/reference.h"
#include "analysis/stability.h"
#include "backends/registry.h"
#include "base/error.h"
#include "core/geometry/quadric.h"
#include "core/geometry/triangle.h"
#include "core/scene_transform.h"
#include "io/loaders/load.h"

namespace rp {
namespace {

using stability::Result;

/// A closed, manifold torus (every edge shared by exactly two triangles).
Scene closed_torus(int major = 48, int minor = 24) {
  TriangleMesh m;
  m.name = "torus";
  for (int i = 0; i < major; ++i)
    for (int j = 0; j < minor; ++j) {
      const double u = 2 * kPi * i / major, v = 2 * kPi * j / minor;
      m.positions.push_back(Vec3f(Vec3d{(1.0 + 0.4 * std::cos(v)) * std::cos(u), 0.4 * std::sin(v),
                                        (1.0 + 0.4 * std::cos(v)) * std::sin(u)}));
    }
  auto at = [&](int i, int j) { return uint32_t((i % major) * minor + (j % minor)); };
  for (int i = 0; i < major; ++i)
    for (int j = 0; j < minor; ++j) {
      for (uint32_t k : {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j), at(i + 1, j + 1), at(i, j + 1)})
        m.indices.push_back(k);
    }
  Scene s;
  s.add_mesh(std::move(m));
  return s;
}

stability::Options options(std::vector<std::string> backends, std::vector<std::string> families, uint32_t rays) {
  stability::Options o;
  o.rays = rays;
  o.backends.clear();
  const std::vector<TraceMethod> available = list_methods();  // those of the available backends
  for (const std::string& b : backends)
    if (std::ranges::count(available, b, &TraceMethod::name) > 0) o.backends.push_back(b);
  o.families = std::move(families);
  o.make_backend = [available](const std::string& method, const Scene& scene) {
    const TraceMethod& m = *std::ranges::find(available, method, &TraceMethod::name);
    return stability::MethodBackend{make_backend(m.backend, scene, m.options()), m.coherence};
  };
  return o;
}

bool simd_available() {
  for (const BackendEntry& e : list_backends())
    if (e.name == "simd") return e.available;
  return false;
}

TEST(Stability, WatertightNeverLeaksThroughAClosedMeshAtAnyTranslationOrScale) {
  if (!simd_available()) GTEST_SKIP() << "simd backend unavailable on this CPU (needs AVX2 and FMA)";
  const Scene torus = closed_torus();
  const auto results = stability::run(torus, options({"simd/watertight:stream", "simd/default:stream"},
                                                     {"edges", "vertices", "translated", "scaled"}, 1500));
  std::set<std::string> seen;
  uint64_t default_leaks = 0;
  for (const Result& r : results) {
    if (r.method == "simd/default:stream") default_leaks += r.counts.leaks;
    if (r.method != "simd/watertight:stream" && r.method != "triangle/watertight") continue;
    seen.insert(r.family + " " + r.param);
    EXPECT_GT(r.counts.rays, 0u) << r.family << " " << r.param;
    EXPECT_EQ(r.counts.leaks, 0u) << r.method << " leaks on " << r.family << " " << r.param;
  }
  // Every translation 10^0..10^7 and every scale was tested.
  for (int k = 0; k <= 7; ++k) EXPECT_TRUE(seen.count("translated 1e" + std::to_string(k))) << k;
  for (int k : {-6, -3, 3, 6}) EXPECT_TRUE(seen.count("scaled 1e" + std::to_string(k))) << k;
  // The families find leaks where there are leaks to find: plain Möller–Trumbore has some.
  EXPECT_GT(default_leaks, 0u);
}

TEST(Stability, NoMethodHitsANaNRayOrOutsideTheRayInterval) {
  const Scene scene = load_scene("default");
  const auto results = stability::run(
      scene, options({"embree/default:single", "embree/robust:single", "simd/default:stream", "simd/watertight:stream"},
                     {}, 256));
  std::set<std::string> families;
  for (const Result& r : results) {
    families.insert(r.family);
    EXPECT_EQ(r.counts.nan_hits, 0u) << r.method << " on " << r.family << " " << r.param;
    EXPECT_EQ(r.counts.out_of_interval, 0u) << r.method << " on " << r.family << " " << r.param;
    EXPECT_LE(r.counts.failed, r.counts.rays);
  }
  // Every family ran (none silently produced no rays on the default scene).
  for (const auto& [name, what] : stability::family_names()) EXPECT_TRUE(families.count(name)) << name;
}

TEST(Stability, OffsetRaysNeverHitTheSurfaceTheyLeaveAtAnyScale) {
  const Scene scene = load_scene("default");
  const auto results = stability::run(
      scene, options({"embree/default:single", "simd/default:stream"}, {"leaving_raw", "leaving_offset"}, 1000));
  uint64_t raw_self = 0, offset_rows = 0;
  for (const Result& r : results) {
    if (r.family == "leaving_raw") raw_self += r.counts.self_hits;
    if (r.family != "leaving_offset") continue;
    ++offset_rows;
    EXPECT_GT(r.counts.rays, 900u) << r.param;
    EXPECT_EQ(r.counts.self_hits, 0u) << r.method << " at " << r.param;
  }
  EXPECT_EQ(offset_rows, (simd_available() ? 2u : 1u) * 12u);  // 8 translations + 4 scales per method
  EXPECT_GT(raw_self, 1000u);  // without the offset, rays do come back to their surface
}

TEST(Stability, FamiliesAreSeededAndSizedAsAsked) {
  const Scene torus = closed_torus(16, 8);
  const auto o = options({"embree/default:single"}, {"edges", "vertices", "nan_inf", "far_spheres"}, 300);
  const auto a = stability::run(torus, o), b = stability::run(torus, o);
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].method, b[i].method);
    EXPECT_EQ(a[i].counts.rays, b[i].counts.rays);
    EXPECT_EQ(a[i].counts.failed, b[i].counts.failed);
    if (a[i].method == "embree/default:single") {
      EXPECT_EQ(a[i].counts.rays, 300u) << a[i].family;
    }
  }
  auto o2 = o;
  o2.families = {"no_such_family"};
  EXPECT_THROW(stability::run(torus, o2), Error);
}

TEST(Stability, FarSpheresSeparateTheNaiveQuadraticFromTheStableForm) {
  const auto results = stability::run(Scene{}, options({}, {"far_spheres"}, 2000));
  double naive = -1, stable = -1;
  for (const Result& r : results) {
    if (r.method == "sphere/naive") naive = r.counts.rate();
    if (r.method == "sphere/stable") stable = r.counts.rate();
  }
  ASSERT_GE(naive, 0.0);
  ASSERT_GE(stable, 0.0);
  EXPECT_GT(naive, 2 * stable);  // cancellation loses whole spheres from 1e4 on
}

TEST(Stability, TransformedSceneGivesTheSameHitsOnTheMovedRays) {
  const Scene scene = load_scene("default");
  const double scale = 4.0;
  const Vec3d offset{3.0, -2.0, 1.0};
  const Scene moved = transformed(scene, scale, offset);
  ASSERT_EQ(moved.prim_count(), scene.prim_count());
  const Reference a(scene), b(moved);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  int hits = 0;
  for (int i = 0; i < 2000; ++i) {
    const Vec3f eye{4.0f * u(rng), 2.0f + u(rng), 6.0f + u(rng)};
    const Ray r{eye, 0.0f, Vec3f{u(rng), u(rng) - 0.3f, -1.0f}, std::numeric_limits<float>::infinity()};
    // The same ray in the moved scene: origin moved (scale is a power of 2, so exact), direction scaled.
    const Ray rm{Vec3f(Vec3d(r.org) * scale + offset), 0.0f, r.dir * float(scale), r.tfar};
    const ReferenceHit ha = a.intersect(r), hb = b.intersect(rm);
    ASSERT_EQ(ha.hit(), hb.hit()) << i;
    if (!ha.hit()) continue;
    ++hits;
    EXPECT_EQ(ha.prim_id, hb.prim_id) << i;
    EXPECT_NEAR(hb.t, ha.t, 1e-4 * ha.t) << i;
  }
  EXPECT_GT(hits, 500);
}

TEST(Stability, MtEpsilonRejectsSmallTrianglesThatPlainMtHits) {
  // The paper's absolute epsilon: a triangle of size 1e-4 seen by a unit ray has det 4e-8.
  const float s = 1e-4f;
  const Vec3f v0{-s, -s, 0.0f}, v1{s, -s, 0.0f}, v2{0.0f, s, 0.0f};
  const Ray r{{0.0f, 0.0f, 1.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, 10.0f};
  EXPECT_TRUE(intersect_triangle_mt(r, v0, v1, v2).hit);
  EXPECT_FALSE(intersect_triangle_mt_epsilon(r, v0, v1, v2).hit);
  const Vec3f big = v0 * 1e4f;  // at unit size both hit
  EXPECT_TRUE(intersect_triangle_mt_epsilon(r, big, v1 * 1e4f, v2 * 1e4f).hit);
}

TEST(Stability, NaiveQuadricAgreesWithTheStableFormWhenWellConditioned) {
  const Quadricf q = Quadricf::ellipsoid({0.5f, 0.25f, 0.0f}, {1.0f, 2.0f, 1.5f});
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  int both = 0;
  for (int i = 0; i < 1000; ++i) {
    const Ray r{{4.0f * u(rng), 4.0f * u(rng), 5.0f}, 0.0f, Vec3f{0.3f * u(rng), 0.3f * u(rng), -1.0f},
                std::numeric_limits<float>::infinity()};
    const auto a = intersect_quadric(r, q), b = intersect_quadric_naive(r, q);
    ASSERT_EQ(a.hit, b.hit) << i;
    if (!a.hit) continue;
    ++both;
    EXPECT_NEAR(a.t, b.t, 1e-4f * a.t) << i;
  }
  EXPECT_GT(both, 100);
}

}  // namespace
}  // namespace rp
