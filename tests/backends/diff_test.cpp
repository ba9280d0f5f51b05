// raypack diff's classification: a backend against itself, a deliberately wrong intersector
// (a test double) and ties on a shared edge, arbitrated by the double-precision reference.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "analysis/diff.h"
#include "analysis/raygen.h"
#include "analysis/reference.h"
#include "backends/registry.h"
#include "tests/support/scenes.h"

namespace rp {
namespace {

std::vector<Hit> trace(const Backend& b, const std::vector<Ray>& rays, Coherence c) {
  std::vector<Hit> hits(rays.size());
  b.intersect(rays, hits, c);
  return hits;
}

std::vector<ReferenceHit> reference_hits(const Scene& s, const std::vector<Ray>& rays) {
  std::vector<ReferenceHit> r(rays.size());
  Reference(s).intersect(rays, r);
  return r;
}

TEST(Diff, EveryBackendAgreesWithItself) {
  const Scene scene = make_default_scene();
  const RaySet set = primary_rays(scene, 64, 48);
  const std::vector<ReferenceHit> ref = reference_hits(scene, set.rays);
  for (const std::string& name : available_backends()) {
    auto b = make_backend(name, scene);
    const std::vector<Hit> h = trace(*b, set.rays, Coherence::coherent);
    const DiffResult d = diff_hits(scene, set.rays, h, h, ref, {});
    EXPECT_EQ(d.agreement(), 1.0) << name;
    EXPECT_EQ(d.count[size_t(DiffClass::agree)], set.rays.size()) << name;
    // And the reference confirms the answer on nearly every ray (all but near-edge rays).
    EXPECT_GE(double(d.support[size_t(DiffClass::agree)].both), 0.99 * double(set.rays.size())) << name;
    EXPECT_EQ(d.support[size_t(DiffClass::agree)].a + d.support[size_t(DiffClass::agree)].b, 0u) << name;
  }
}

/// A test double: a real backend whose answers are broken on purpose, ray by ray.
class WrongBackend final : public ForwardingBackend {
 public:
  WrongBackend(const Scene& scene, std::unique_ptr<Backend> real) : ForwardingBackend(scene, std::move(real)) {}

 private:
  void trace_closest(std::span<const Ray> rays, std::span<Hit> hits, Coherence c) const noexcept override {
    inner().intersect(rays, hits, c);
    for (size_t i = 0; i < rays.size(); ++i) {
      if (!hits[i].hit()) continue;
      switch (i % 10) {
        case 1: hits[i] = Hit{}; break;                                   // a leak
        case 2: hits[i].t *= 1.001f; break;                               // t off by 1e-3
        case 3: hits[i].prim_id ^= 1u; hits[i].t *= 1.01f; break;         // wrong primitive, farther
        default: break;
      }
    }
  }
};

TEST(Diff, ADeliberatelyWrongIntersectorIsCaughtAndClassified) {
  // A mesh only, so every hit's neighbour id (prim ^ 1) is another triangle.
  const Scene def = make_default_scene();
  Scene scene;
  TriangleMesh knot = to_triangle_mesh(def.meshes()[0]);
  knot.material = 0;
  scene.add_mesh(knot);
  scene.set_camera(*def.camera());
  const RaySet set = primary_rays(scene, 64, 64);
  auto good = make_backend("embree", scene);
  const WrongBackend bad(scene, make_backend("embree", scene));
  const std::vector<Hit> a = trace(*good, set.rays, Coherence::coherent);
  const std::vector<Hit> b = trace(bad, set.rays, Coherence::coherent);
  size_t leaks = 0, t_off = 0, wrong = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    if (!a[i].hit()) continue;
    leaks += i % 10 == 1;
    t_off += i % 10 == 2;
    wrong += i % 10 == 3;
  }
  ASSERT_GT(leaks, 50u);
  const DiffResult d = diff_hits(scene, set.rays, a, b, reference_hits(scene, set.rays), {});
  EXPECT_EQ(d.count[size_t(DiffClass::hit_miss)], leaks);
  EXPECT_EQ(d.count[size_t(DiffClass::t_error)], t_off);
  EXPECT_EQ(d.count[size_t(DiffClass::wrong_prim)], wrong);
  EXPECT_EQ(d.count[size_t(DiffClass::tie)], 0u);
  // The reference sides with the real intersector on every broken ray, except rays within
  // a hair of an edge where the reference and Embree may choose differently.
  for (DiffClass c : {DiffClass::hit_miss, DiffClass::t_error, DiffClass::wrong_prim}) {
    const Support& s = d.support[size_t(c)];
    EXPECT_EQ(s.b, 0u) << to_string(c);
    EXPECT_GE(double(s.a), 0.99 * double(d.count[size_t(c)])) << to_string(c);
  }
  EXPECT_NEAR(d.agreement(), 1.0 - double(leaks + t_off + wrong) / double(a.size()), 1e-12);
}

TEST(Diff, RaysThroughASharedEdgeAreTies) {
  // The unit square at z = 0 as two triangles sharing the diagonal from (0,0) to (1,1).
  Scene scene;
  TriangleMesh quad;
  quad.name = "quad";
  quad.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  quad.indices = {0, 1, 2, 0, 2, 3};
  scene.add_mesh(quad);
  std::vector<Ray> rays;
  for (int k = 1; k < 64; ++k) {
    const float s = float(k) / 64.0f;  // exactly on the diagonal
    rays.push_back({{s, s, 1.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, 10.0f});
  }
  // A says triangle 0, B says triangle 1, at the same t: exactly what two correct backends
  // may answer on a shared edge.
  std::vector<Hit> a(rays.size(), Hit{1.0f, 0, 0.5f, 0.5f}), b(rays.size(), Hit{1.0f, 1, 0.5f, 0.0f});
  b[3].t = std::nextafter(1.0f, 2.0f);  // a rounding apart is still a tie
  const std::vector<ReferenceHit> ref = reference_hits(scene, rays);
  for (const ReferenceHit& r : ref) {
    EXPECT_TRUE(r.hit()) << "the watertight reference never leaks through the shared edge";
    EXPECT_EQ(r.t, 1.0);
  }
  const DiffResult d = diff_hits(scene, rays, a, b, ref, {});
  EXPECT_EQ(d.count[size_t(DiffClass::tie)], rays.size());
  EXPECT_EQ(d.agreement(), 1.0);
  // The reference hits one of the two at t = 1: it supports the side with its primitive.
  const Support& s = d.support[size_t(DiffClass::tie)];
  EXPECT_EQ(s.a + s.b + s.both, rays.size());
}

TEST(Diff, OnePrimitiveThroughTwoInstancesIsTwoPrimitives) {
  // A triangle placed twice: the same prim_id in another instance is another primitive of the
  // world, a tie at the same t and a wrong primitive farther away; instanced hits of every
  // backend agree with each other and with the reference, instance included.
  Scene scene;
  TriangleMesh tri;
  tri.name = "tri";
  tri.positions = {{-1, -1, 0}, {1, -1, 0}, {0, 1, 0}};
  tri.indices = {0, 1, 2};
  const uint32_t m = scene.add_instanced_mesh(tri);
  Affine3f at;
  scene.add_instance(m, at);
  at.m[2][3] = -1.0f;
  scene.add_instance(m, at);
  const std::vector<Ray> rays(8, Ray{{0.1f, -0.2f, 2.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, 10.0f});
  const std::vector<ReferenceHit> ref = reference_hits(scene, rays);
  ASSERT_EQ(ref[0].instance_id, 0u);
  std::vector<Hit> a(rays.size(), Hit{2.0f, 0, 0.3f, 0.35f, 0}), b = a;
  b[1].instance_id = 1;              // the same t: a tie
  b[2] = Hit{3.0f, 0, 0.3f, 0.35f, 1};  // the second placement, behind: a wrong primitive
  const DiffResult d = diff_hits(scene, rays, a, b, ref, {});
  EXPECT_EQ(d.per_ray[0], DiffClass::agree);
  EXPECT_EQ(d.per_ray[1], DiffClass::tie);
  EXPECT_EQ(d.per_ray[2], DiffClass::wrong_prim);
  EXPECT_EQ(d.support[size_t(DiffClass::wrong_prim)].a, 1u);  // the reference hits instance 0 at t = 2
  for (const std::string& name : available_backends()) {
    const std::vector<Hit> h = trace(*make_backend(name, scene), rays, Coherence::coherent);
    const DiffResult self = diff_hits(scene, rays, h, a, ref, {});
    EXPECT_EQ(self.count[size_t(DiffClass::agree)], rays.size()) << name;
  }
}

TEST(Diff, EmbreeAndSimdAgreeOnEveryRayThroughInstances) {
  // 144 placements of a fine sphere (rotated, scaled unevenly, one in four mirrored) up to 40
  // units from the origin, where an object-space ray one ulp off reaches another triangle on
  // a silhouette and another t in a crevice. Both backends map a world ray into an instance
  // with the same float arithmetic (rp::float_inverse, rp::object_ray: Embree's own), so
  // whatever their triangle tests, they meet the same object-space rays and agree on every
  // one, as on world meshes. (With the correctly rounded inverse, the double one rounded to
  // float, 6 of these rays disagreed: 1 random ray, 5 diffuse ones.)
  const std::vector<std::string> names = available_backends();
  if (std::find(names.begin(), names.end(), "simd") == names.end())
    GTEST_SKIP() << "the simd backend is not available on this CPU (needs AVX2 and FMA): nothing to compare embree with";
  const Scene ball = test::tessellated_sphere(96, 48);
  Scene scene;
  const uint32_t m = scene.add_instanced_mesh(ball.meshes()[0]);
  for (int i = 0; i < 144; ++i) {
    const float s = 0.3f + 0.05f * float(i % 7), mirror = i % 4 == 3 ? -1.0f : 1.0f;
    scene.add_instance(m, test::placement({mirror * s, s * 0.7f, s * 1.1f}, {float(i % 3), 1.0f, 0.5f},
                                          13.0f * float(i), {float(i % 12) * 1.1f + 28.0f, float(i / 12) * 1.1f, 3.0f}));
  }
  auto embree = make_backend("embree", scene), simd = make_backend("simd", scene);
  const RaySet primary = primary_rays(scene, 320, 240);
  const std::vector<Hit> primary_hits = trace(*embree, primary.rays, Coherence::coherent);
  const RaySet sets[] = {primary, random_rays(scene, 60000, 7), diffuse_rays(scene, primary, primary_hits, 3)};
  const Coherence coherences[] = {Coherence::coherent, Coherence::incoherent, Coherence::incoherent};
  for (int k = 0; k < 3; ++k) {
    const std::vector<Ray>& rays = sets[k].rays;
    const std::vector<Hit> a = trace(*embree, rays, coherences[k]), b = trace(*simd, rays, coherences[k]);
    const DiffResult d = diff_hits(scene, rays, a, b, reference_hits(scene, rays), {});
    size_t hits = 0;
    for (const Hit& h : a) hits += h.hit();
    EXPECT_GT(hits, rays.size() / 10) << "ray set " << k << ": too few rays meet the instances to test them";
    EXPECT_EQ(d.count[size_t(DiffClass::agree)] + d.count[size_t(DiffClass::tie)], rays.size())
        << "ray set " << k << ": hit/miss " << d.count[size_t(DiffClass::hit_miss)] << ", wrong primitive "
        << d.count[size_t(DiffClass::wrong_prim)] << ", t error " << d.count[size_t(DiffClass::t_error)];
  }
}

TEST(Diff, TableAndJsonNameEveryClass) {
  const Scene scene = make_default_scene();
  const RaySet set = primary_rays(scene, 16, 16);
  auto e = make_backend("embree", scene);
  const std::vector<Hit> h = trace(*e, set.rays, Coherence::coherent);
  const DiffResult d = diff_hits(scene, set.rays, h, h, reference_hits(scene, set.rays), {});
  const std::string table = format_table(d, "embree/default", "embree/default");
  const std::string json = to_json(d, "default", "primary", "embree/default", "embree/default", {});
  for (int c = 0; c < kDiffClasses; ++c) {
    EXPECT_NE(table.find(to_string(DiffClass(c))), std::string::npos) << table;
    EXPECT_NE(json.find(std::string("\"") + to_string(DiffClass(c)) + "\""), std::string::npos) << json;
  }
  EXPECT_NE(json.find("\"agreement\": 1.0"), std::string::npos) << json;
  const Image img = mismatch_image(d, set, h);
  EXPECT_EQ(img.width, 16);
  EXPECT_EQ(img.height, 16);
}

}  // namespace
}  // namespace rp
