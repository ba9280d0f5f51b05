// Backend conformance: every available backend against the brute-force double-precision
// oracle on seeded random scenes and rays, for both coherence hints, intersect and occluded.

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <tuple>

#include "backends/registry.h"
#include "base/error.h"
#include "oracle.h"
#include "render/camera.h"
#include "render/render.h"
#include "tests/support/scenes.h"

namespace rp {
namespace {

using test::analytic_scene;
using test::axis_rays;
using test::oracle_ambiguous;
using test::oracle_intersect;
using test::OracleHit;
using test::random_direction;
using test::random_in_box;
using test::random_rays;
using test::tessellated_sphere;
using test::triangle_soup;

/// Every variant of every available backend, as "backend/variant", and every other coherent
/// method of its default variant, as "backend/default@method" (coherent) or
/// "backend/default@incoherent-method" (a backend may name both kinds alike): the conformance
/// suite holds each of them to the same oracle.
std::vector<std::string> backend_variants() {
  std::vector<std::string> out;
  for (const BackendEntry& b : list_backends())
    if (b.available) {
      for (const std::string& v : b.variants) out.push_back(b.name + "/" + v);
      for (size_t m = 1; m < b.coherent_methods.size(); ++m) out.push_back(b.name + "/default@" + b.coherent_methods[m]);
      for (size_t m = 1; m < b.incoherent_methods.size(); ++m)
        out.push_back(b.name + "/default@incoherent-" + b.incoherent_methods[m]);
    }
  return out;
}

std::unique_ptr<Backend> make_param_backend(const std::string& param, const Scene& scene) {
  const size_t slash = param.find('/'), at = param.find('@');
  const std::string variant = param.substr(slash + 1, at == std::string::npos ? std::string::npos : at - slash - 1);
  const std::string name = param.substr(0, slash);
  std::string method = at == std::string::npos ? std::string() : param.substr(at + 1);
  const std::string incoherent_prefix = "incoherent-";
  const bool coherent = !method.starts_with(incoherent_prefix);
  if (!coherent) method = method.substr(incoherent_prefix.size());
  return make_backend(name, scene, {.variant = variant, .device_config = {}, .coherent_method = coherent ? method : "",
                                    .incoherent_method = coherent ? "" : method});
}

struct Counts {
  int rays = 0, hits = 0, ambiguous = 0;
};

/// Checks every ray of one batch against the oracle's answers `refs` (one per ray); returns how
/// many disagreements were excused as ambiguous (grazing) rays. Same-primitive hits must agree
/// in t to 1e-4 relative.
Counts check_against_oracle(const Scene& scene, const Backend& backend, const std::vector<Ray>& rays,
                            const std::vector<OracleHit>& refs, Coherence coherence, const std::string& what) {
  std::vector<Hit> hits(rays.size());
  std::vector<uint8_t> occ(rays.size());
  backend.intersect(rays, hits, coherence);
  backend.occluded(rays, occ, coherence);
  Counts c;
  const float delta = 1e-4f * std::max(1.0f, max_component(abs(scene.bounds().extent())));
  for (size_t i = 0; i < rays.size(); ++i) {
    const OracleHit& ref = refs[i];
    const Hit& h = hits[i];
    ++c.rays;
    c.hits += ref.hit();
    const bool same = h.prim_id == ref.prim_id;
    bool t_ok = true;
    if (same && h.hit()) {
      EXPECT_TRUE(h.t >= rays[i].tnear && h.t <= rays[i].tfar) << what << " ray " << i << " t " << h.t;
      t_ok = std::abs(h.t - ref.t) <= 1e-4 * std::max(1.0, ref.t);
      if (t_ok && scene.locate(h.prim_id).kind == PrimKind::triangle) {
        EXPECT_NEAR(h.u, ref.u, 1e-3) << what << " ray " << i;
        EXPECT_NEAR(h.v, ref.v, 1e-3) << what << " ray " << i;
      }
    }
    const bool occ_ok = bool(occ[i]) == ref.hit();
    if (same && t_ok && occ_ok) continue;
    if (oracle_ambiguous(scene, rays[i], delta)) {
      ++c.ambiguous;
      if (std::getenv("RP_SHOW_AMBIGUOUS"))
        std::printf("ambiguous %s ray %zu org (%g %g %g) dir (%g %g %g): backend %u t %g, oracle %u t %g\n", what.c_str(), i,
                    rays[i].org.x, rays[i].org.y, rays[i].org.z, rays[i].dir.x, rays[i].dir.y, rays[i].dir.z, h.prim_id,
                    h.t, ref.prim_id, ref.t);
      continue;
    }
    ADD_FAILURE() << what << " ray " << i << " org (" << rays[i].org.x << ", " << rays[i].org.y << ", "
                  << rays[i].org.z << ") dir (" << rays[i].dir.x << ", " << rays[i].dir.y << ", " << rays[i].dir.z
                  << ") [" << rays[i].tnear << ", " << rays[i].tfar << "]: backend prim " << h.prim_id << " t "
                  << h.t << " occluded " << int(occ[i]) << ", oracle prim " << ref.prim_id << " t " << ref.t;
  }
  return c;
}

class Conformance : public ::testing::TestWithParam<std::string> {
 protected:
  /// `max_ambiguous`: the fraction of rays that may disagree with the oracle where the oracle
  /// itself is ill-conditioned (1% for random rays; more for rays aimed along boundaries).
  void check_scene(const Scene& scene, const std::vector<Ray>& rays, const std::string& name, int min_hits,
                   double max_ambiguous = 0.01) {
    auto backend = make_param_backend(GetParam(), scene);
    // The oracle's answers depend on the scene and the rays only: worked out once for both hints.
    std::vector<OracleHit> refs;
    refs.reserve(rays.size());
    for (const Ray& r : rays) refs.push_back(oracle_intersect(scene, r));
    for (Coherence coh : {Coherence::coherent, Coherence::incoherent}) {
      const std::string what = name + (coh == Coherence::coherent ? "/coherent" : "/incoherent");
      const Counts c = check_against_oracle(scene, *backend, rays, refs, coh, what);
      EXPECT_GE(c.hits, min_hits) << what << ": the rays must actually hit the scene";
      EXPECT_LE(c.ambiguous, int(max_ambiguous * c.rays)) << what << ": too many disagreements excused as grazing";
    }
  }
};

TEST_P(Conformance, TriangleSoupMatchesOracle) {
  check_scene(triangle_soup(7, 1500), random_rays(11, 4000), "soup", 1000);
}

TEST_P(Conformance, TessellatedSphereMatchesOracle) {
  check_scene(tessellated_sphere(48, 24), random_rays(12, 4000), "uv_sphere", 1000);
}

TEST_P(Conformance, AnalyticPrimitivesMatchOracle) {
  check_scene(analytic_scene(), random_rays(13, 8000), "analytic", 2000);
}

TEST_P(Conformance, AxisParallelRaysWithSignedZerosMatchOracle) {
  // The grid of origins (multiples of 0.25) puts many rays exactly on polygon edges and clip
  // planes of the analytic scene (about 2.5% of them): allow 5% there.
  check_scene(analytic_scene(), axis_rays(), "analytic/axis", 200, 0.05);
  check_scene(triangle_soup(8, 800), axis_rays(), "soup/axis", 100);
}

TEST_P(Conformance, DefaultSceneMatchesOracle) {
  const Scene scene = make_default_scene();
  const Camera cam(*scene.camera(), 48, 32);
  std::vector<Ray> rays;
  for (int y = 0; y < 32; y += 2)
    for (int x = 0; x < 48; x += 4)
      for (int lane = 0; lane < 8; ++lane) rays.push_back(cam.generate(x + lane % 4 + 0.5f, y + lane / 4 + 0.5f));
  check_scene(scene, rays, "default", 1000);
}

TEST_P(Conformance, InstancedMeshesMatchOracle) {
  const Scene scene = test::instanced_scene();
  check_scene(scene, random_rays(15, 4000), "instanced", 1000);
  check_scene(scene, axis_rays(), "instanced/axis", 100, 0.05);
}

/// The instances' hits carry the instance and the mesh's own prim id, and name the same point
/// (and normal) as the triangles baked into the world in the flattened scene: the same hit or
/// miss and t within 1e-5 (relative) on every ray the oracle finds well-conditioned.
TEST_P(Conformance, InstancesHitWhereTheirTrianglesBakedIntoTheWorldDo) {
  const Scene scene = test::instanced_scene(), flat = test::flattened(scene);
  auto a = make_param_backend(GetParam(), scene), b = make_param_backend(GetParam(), flat);
  const std::vector<Ray> rays = random_rays(16, 4000);
  std::vector<Hit> ha(rays.size()), hb(rays.size());
  int instance_hits = 0, compared = 0;
  const float delta = 1e-4f * max_component(abs(scene.bounds().extent()));
  for (Coherence coh : {Coherence::coherent, Coherence::incoherent}) {
    a->intersect(rays, ha, coh);
    b->intersect(rays, hb, coh);
    for (size_t i = 0; i < rays.size(); ++i) {
      if (ha[i].instance_id != kNoInstance) {
        ++instance_hits;
        const Instance& in = scene.instances()[ha[i].instance_id];
        EXPECT_GE(ha[i].prim_id, scene.mesh_base(in.mesh)) << "ray " << i;
        EXPECT_LT(ha[i].prim_id, scene.mesh_base(in.mesh) + scene.meshes()[in.mesh].triangle_count()) << "ray " << i;
      } else if (ha[i].hit()) {
        EXPECT_FALSE(scene.locate(ha[i].prim_id).kind == PrimKind::triangle && scene.is_instanced(scene.locate(ha[i].prim_id).shape))
            << "ray " << i << ": an instanced mesh's triangle without an instance";
      }
      if (ha[i].hit() != hb[i].hit() || (ha[i].hit() && std::abs(ha[i].t - hb[i].t) > 1e-5f * hb[i].t)) {
        if (oracle_ambiguous(scene, rays[i], delta) || oracle_ambiguous(flat, rays[i], delta)) continue;
        ADD_FAILURE() << "ray " << i << ": instanced t " << ha[i].t << " prim " << ha[i].prim_id << " instance "
                      << ha[i].instance_id << ", flattened t " << hb[i].t << " prim " << hb[i].prim_id;
      }
      ++compared;
      if (ha[i].instance_id == kNoInstance || !hb[i].hit()) continue;
      // The same point and (up to rounding) the same geometric normal, in world space.
      const SurfacePoint pa = scene.surface(rays[i], ha[i]), pb = flat.surface(rays[i], hb[i]);
      EXPECT_LT(length(pa.position - pb.position), 1e-4f) << "ray " << i;
      EXPECT_GT(dot(pa.geometric_normal, pb.geometric_normal), 0.999f) << "ray " << i;
    }
  }
  EXPECT_GE(instance_hits, 800);  // 2 x 4000 rays: about an eighth hit an instance
  EXPECT_GE(compared, 7900);
}

TEST_P(Conformance, EmptySceneAlwaysMisses) {
  Scene scene;
  auto backend = make_param_backend(GetParam(), scene);
  const std::vector<Ray> rays = random_rays(14, 64);
  std::vector<Hit> hits(rays.size(), Hit{1.0f, 3, 0.5f, 0.5f});
  std::vector<uint8_t> occ(rays.size(), 1);
  for (Coherence coh : {Coherence::coherent, Coherence::incoherent}) {
    backend->intersect(rays, hits, coh);
    backend->occluded(rays, occ, coh);
    for (size_t i = 0; i < rays.size(); ++i) {
      EXPECT_FALSE(hits[i].hit());
      EXPECT_EQ(hits[i].t, std::numeric_limits<float>::infinity());
      EXPECT_EQ(occ[i], 0);
    }
  }
}

/// The interval convention tnear <= t <= tfar, at exactly representable hits.
TEST_P(Conformance, HitCountsOnlyWithinClosedInterval) {
  Scene scene;
  TriangleMesh quad;  // the square |x|,|y| <= 1 at z = 2
  quad.name = "quad";
  quad.positions = {{-1, -1, 2}, {1, -1, 2}, {1, 1, 2}, {-1, 1, 2}};
  quad.indices = {0, 1, 2, 0, 2, 3};
  scene.add_mesh(quad);
  scene.add_sphere({{0.0f, 0.0f, -3.0f}, 1.0f, 0});  // surface at z = -2
  auto backend = make_param_backend(GetParam(), scene);
  const float below = std::nextafter(2.0f, 0.0f), above = std::nextafter(2.0f, 4.0f);
  struct Case { Vec3f dir; float tnear, tfar; bool hit; };
  const Case cases[] = {
      {{0.25f, -0.125f, 1.0f}, 0.0f, 2.0f, true},  {{0.25f, -0.125f, 1.0f}, 0.0f, below, false},
      {{0.25f, -0.125f, 1.0f}, 2.0f, 9.0f, true},  {{0.25f, -0.125f, 1.0f}, above, 9.0f, false},
      {{0.0f, 0.0f, -1.0f}, 0.0f, 2.0f, true}, {{0.0f, 0.0f, -1.0f}, 0.0f, below, false},
      {{0.0f, 0.0f, -1.0f}, 2.0f, 2.0f, true}, {{0.0f, 0.0f, -1.0f}, above, 9.0f, true},  // far side at z = -4
  };
  for (Coherence coh : {Coherence::coherent, Coherence::incoherent})
    for (const Case& c : cases) {
      const Ray r{{0.0f, 0.0f, 0.0f}, c.tnear, c.dir, c.tfar};
      Hit h;
      uint8_t occ = 0;
      backend->intersect({&r, 1}, {&h, 1}, coh);
      backend->occluded({&r, 1}, {&occ, 1}, coh);
      EXPECT_EQ(h.hit(), c.hit) << "dir z " << c.dir.z << " [" << c.tnear << ", " << c.tfar << "]";
      EXPECT_EQ(bool(occ), c.hit) << "dir z " << c.dir.z << " [" << c.tnear << ", " << c.tfar << "]";
      if (h.hit()) {
        EXPECT_TRUE(h.t >= c.tnear && h.t <= c.tfar);
      }
    }
}

TEST_P(Conformance, InvalidRaysMissAndAreNotOccluded) {
  // NaN and infinite components, a zero direction, tnear outside [0, tfar], and finite rays
  // beyond the range of core/ray.h (Embree aborts from 1.844e18 up): misses everywhere,
  // never passed to an engine, however squarely they aim at the geometry.
  const Scene scene = analytic_scene();
  auto backend = make_param_backend(GetParam(), scene);
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const float past = std::nextafter(kMaxCoordinate, 2 * kMaxCoordinate);
  const std::vector<Ray> rays = {
      {{nan, 0, 4}, 0, {0, 0, -1}, inf}, {{0, 0, 4}, 0, {0, nan, -1}, inf}, {{0, 0, 4}, nan, {0, 0, -1}, inf},
      {{0, 0, 4}, 0, {0, 0, -1}, nan},   {{0, 0, 4}, 5, {0, 0, -1}, 1},     {{0, 0, 4}, 0, {0, 0, 0}, inf},
      {{inf, 0, 4}, 0, {0, 0, -1}, inf}, {{0, 0, 4}, 0, {0, 0, -inf}, inf}, {{0, 0, 4}, -1, {0, 0, -1}, inf},
      {{0, 0, 1e19f}, 0, {0, 0, -1}, inf},           {{0, 0, past}, 0, {0, 0, -1}, inf},
      {{0, 0, 4}, 0, {0, 0, -1e19f}, inf},           {{0, 0, 4}, 0, {0, 0, -2 * kMaxDirection}, inf},
      {{0, 0, 4}, 0, {0, 0, -1e-30f}, inf},          {{0, 0, 4}, 0, {0, 0, -0.5f * kMinDirection}, inf},
      {{0, 0, 4}, 0, {1e-40f, 1e-40f, -1e-39f}, inf}, {{-3e38f, 0, 4}, 0, {3e38f, 0, -4}, inf},
  };
  std::vector<Hit> hits(rays.size());
  std::vector<uint8_t> occ(rays.size(), 1);
  for (Coherence coh : {Coherence::coherent, Coherence::incoherent}) {
    backend->intersect(rays, hits, coh);
    backend->occluded(rays, occ, coh);
    for (size_t i = 0; i < rays.size(); ++i) {
      EXPECT_FALSE(hits[i].hit()) << "ray " << i;
      EXPECT_EQ(occ[i], 0) << "ray " << i;
    }
  }
}

TEST_P(Conformance, DirectionsAtTheEndsOfTheRangeAreTraced) {
  // The largest component at 2^31 and at 2^-26; origins at the range's edge: ExtremeScales...
  const Scene scene = analytic_scene();
  auto backend = make_param_backend(GetParam(), scene);
  const float inf = std::numeric_limits<float>::infinity();
  const std::vector<Ray> inside = {{{0, 0, 4}, 0, {0, 0, -kMaxDirection}, inf}, {{0, 0, 4}, 0, {0, 0, -kMinDirection}, inf}};
  std::vector<Hit> in_hits(inside.size());
  for (Coherence coh : {Coherence::coherent, Coherence::incoherent}) {
    backend->intersect(inside, in_hits, coh);
    for (size_t i = 0; i < inside.size(); ++i) EXPECT_EQ(in_hits[i].prim_id, scene.sphere_base()) << "ray " << i;
  }
}

/// Geometry at the edges of the coordinate range: a triangle spanning the whole range, a small
/// one in a corner, a sphere, an ellipsoid and a polygon far out.
Scene extreme_scene() {
  constexpr float R = kMaxCoordinate;
  Scene s;
  TriangleMesh m;
  m.name = "extreme";
  m.positions = {{-R, -R, 0.5f * R}, {R, -R, 0.5f * R}, {0, R, 0.5f * R},  // spans the range at z = 2^29
                 {R - 0x1p23f, R - 0x1p23f, -R + 0x1p22f}, {R - 0x1p22f, R - 0x1p23f, -R + 0x1p23f},
                 {R - 0x1p23f, R - 0x1p22f, -R + 0x1p22f}};  // a small one near a corner
  m.indices = {0, 1, 2, 3, 4, 5};
  s.add_mesh(m);
  s.add_sphere({{-0.5f * R, 0.5f * R, 0}, 0.25f * R, 0});
  s.add_quadric({Quadricf::ellipsoid({0.5f * R, -0.5f * R, 0}, {0.125f * R, 0.0625f * R, 0.125f * R}), 0});
  const std::vector<Vec3f> polygon{{-0.875f * R, -0.875f * R, -0.875f * R}, {-0.625f * R, -0.875f * R, -0.875f * R},
                                   {-0.625f * R, -0.625f * R, -0.875f * R}, {-0.875f * R, -0.625f * R, -0.875f * R}};
  s.add_polygon(polygon, 0);
  // A general quadric with cross terms at the origin: seen from a corner along the diagonal
  // with a 2^31 direction, b^2 of its quadratic overflows float unless the direction is scaled.
  Quadricf q;
  q.A = q.B = q.C = q.D = q.E = q.F = 1;
  q.J = -1;
  q.clip = {Vec3f(-2.0f), Vec3f(2.0f)};
  s.add_quadric({q, 0});
  return s;
}

TEST_P(Conformance, ExtremeScalesWithinTheRangeGiveTheOraclesHits) {
  // Origins at the range's corners, aimed at the middle of each primitive, with directions
  // whose largest component is 2^31, 1 and 2^-26: no kernel may overflow into a miss, a false
  // hit or a zero normal (the far-from-origin failures of hostile input round two).
  const Scene scene = extreme_scene();
  auto backend = make_param_backend(GetParam(), scene);
  constexpr float R = kMaxCoordinate;
  const std::vector<Vec3f> targets = {{0, -0x1p28f, 0.5f * R},  // the centroids and centres
                                      (scene.meshes()[0].vertex(1, 0) + scene.meshes()[0].vertex(1, 1) +
                                       scene.meshes()[0].vertex(1, 2)) * (1.0f / 3.0f),
                                      {-0.5f * R, 0.5f * R, 0},
                                      {0.5f * R, -0.5f * R, 0},
                                      {-0.75f * R, -0.75f * R, -0.875f * R},
                                      {0, 0, 0}};
  std::vector<Ray> rays;
  for (float x : {-1.0f, 1.0f})
    for (float y : {-1.0f, 1.0f})
      for (float z : {-1.0f, 1.0f})
        for (const Vec3f& t : targets)
          for (float largest : {kMaxDirection, 1.0f, kMinDirection}) {
            const Vec3f o = Vec3f{x, y, z} * kMaxCoordinate;
            Vec3f d = t - o;
            d = d * (largest / max_component(abs(d)));
            rays.push_back({o, 0.0f, d, std::numeric_limits<float>::infinity()});
          }
  std::vector<Hit> hits(rays.size());
  int checked = 0;
  for (Coherence coh : {Coherence::coherent, Coherence::incoherent}) {
    backend->intersect(rays, hits, coh);
    for (size_t i = 0; i < rays.size(); ++i) {
      const OracleHit o = oracle_intersect(scene, rays[i]);
      ASSERT_EQ(hits[i].prim_id, o.prim_id) << "ray " << i;
      if (!o.hit()) continue;
      ++checked;
      EXPECT_NEAR(double(hits[i].t) / o.t, 1.0, 1e-4) << "ray " << i;
      const SurfacePoint sp = scene.surface(rays[i], hits[i]);
      EXPECT_NEAR(length(Vec3d(sp.geometric_normal)), 1.0, 1e-4) << "ray " << i << ": normal not unit";
    }
  }
  EXPECT_GE(checked, 2 * 70);
}

/// The image of `scene` rendered with at most `threads` worker threads.
std::vector<float> render_with_threads(const Scene& scene, const Backend& backend, const Camera& cam,
                                       const RenderSettings& st, int threads) {
  tbb::global_control c(tbb::global_control::max_allowed_parallelism, size_t(threads));
  return render(scene, backend, cam, st).image.rgb;
}

TEST_P(Conformance, RenderIsBitIdenticalForOneAndTwoThreads) {
  const Scene scene = make_default_scene();
  auto backend = make_param_backend(GetParam(), scene);
  CameraDesc lens = *scene.camera();
  lens.model = CameraModel::thin_lens;
  lens.aperture = 0.2f;
  for (const auto& [desc, sampler, spp] : {std::tuple{*scene.camera(), Sampler::stratified, 4},
                                           std::tuple{lens, Sampler::random, 3},
                                           std::tuple{*scene.camera(), Sampler::adaptive, 1}}) {
    const Camera cam(desc, 67, 45);  // odd sizes: partial tiles and packets
    RenderSettings st;
    st.width = 67;
    st.height = 45;
    st.spp = spp;
    st.sampler = sampler;
    st.seed = 1234;
    const std::vector<float> one = render_with_threads(scene, *backend, cam, st, 1),
                             two = render_with_threads(scene, *backend, cam, st, 2);
    ASSERT_EQ(one.size(), two.size());
    EXPECT_EQ(0, std::memcmp(one.data(), two.data(), one.size() * sizeof(float))) << int(sampler);
    EXPECT_EQ(one, render(scene, *backend, cam, st).image.rgb) << int(sampler);  // and across runs
  }
}

TEST_P(Conformance, InstancedRenderIsBitIdenticalForOneAndTwoThreads) {
  Scene scene = test::instanced_scene();
  scene.add_light(PointLight{{2.0f, 3.0f, 2.5f}, {12.0f, 12.0f, 12.0f}});
  auto backend = make_param_backend(GetParam(), scene);
  const Camera cam(frame_bounds(scene.bounds()), 53, 37);
  RenderSettings st;
  st.width = 53;
  st.height = 37;
  st.spp = 2;
  st.seed = 99;
  const std::vector<float> one = render_with_threads(scene, *backend, cam, st, 1),
                           two = render_with_threads(scene, *backend, cam, st, 2);
  ASSERT_EQ(one.size(), two.size());
  EXPECT_EQ(0, std::memcmp(one.data(), two.data(), one.size() * sizeof(float)));
}

INSTANTIATE_TEST_SUITE_P(Backends, Conformance, ::testing::ValuesIn(backend_variants()), [](const auto& info) {
  std::string name = info.param;
  std::replace(name.begin(), name.end(), '/', '_');
  std::replace(name.begin(), name.end(), '@', '_');
  std::replace(name.begin(), name.end(), '-', '_');
  return name;
});

TEST(Registry, UnknownBackendIsAnErrorListingTheNames) {
  const Scene scene;
  try {
    make_backend("nope", scene);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "unknown backend 'nope' (available: embree, simd)");
  }
}

TEST(Registry, SimdIsOfferedExactlyWhenTheCpuHasAvx2AndFma) {
  __builtin_cpu_init();
  const bool cpu = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  const std::vector<BackendEntry> all = list_backends();
  const auto it = std::find_if(all.begin(), all.end(), [](const BackendEntry& e) { return e.name == "simd"; });
  ASSERT_NE(it, all.end());
  EXPECT_EQ(it->available, cpu);
  const Scene scene;
  if (!it->available) {
    EXPECT_FALSE(it->unavailable_reason.empty());
    try {
      make_backend("simd", scene);
      ADD_FAILURE() << "an unavailable backend was built";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(it->unavailable_reason), std::string::npos) << e.what();
    }
    GTEST_SKIP() << "simd backend not run: " << it->unavailable_reason;
  }
  EXPECT_EQ(make_backend("simd", scene)->info().name, "simd");
}

TEST(Registry, UnknownVariantOrMethodIsAnError) {
  const Scene scene;
  EXPECT_THROW(make_backend("embree", scene, {.variant = "fastest", .device_config = {}, .coherent_method = {}, .incoherent_method = {}}), Error);
  EXPECT_THROW(make_backend("simd", scene, {.variant = "fastest", .device_config = {}, .coherent_method = {}, .incoherent_method = {}}), Error);
  EXPECT_THROW(make_backend("embree", scene, {.variant = "default", .device_config = {}, .coherent_method = "large", .incoherent_method = {}}), Error);
  EXPECT_THROW(make_backend("simd", scene, {.variant = "default", .device_config = {}, .coherent_method = "stream", .incoherent_method = {}}), Error);
  EXPECT_THROW(
      make_backend("embree", scene,
                   {.variant = "default", .device_config = {}, .coherent_method = {}, .incoherent_method = "large"}),
      Error);
  EXPECT_THROW(make_backend("simd", scene, {.variant = "default", .device_config = {}, .coherent_method = {}, .incoherent_method = "packet8"}), Error);
}

}  // namespace
}  // namespace rp
