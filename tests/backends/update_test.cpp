// Scenes that move: after every kind of change, an updated backend answers as a backend built
// afresh from the changed scene, bit for bit, by every ray shape; a backend whose scene changed
// refuses to trace until updated; update() does the least work the change needs.

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "analysis/reference.h"
#include "backends/registry.h"
#include "base/error.h"
#include "tests/support/error_of.h"
#include "tests/support/scenes.h"
#include "tests/support/variants.h"

namespace rp {
namespace {

BackendOptions options(const std::string& variant, double refit_limit = BackendOptions{}.refit_limit) {
  BackendOptions o;
  o.variant = variant;
  o.refit_limit = refit_limit;
  return o;
}

/// The test's scene: instanced_scene() (two instanced meshes placed five times, a world floor,
/// a sphere, a quadric, a plane) and a closed tessellated sphere as a world mesh (mesh 3).
Scene moving_scene() {
  Scene s = test::instanced_scene();
  TriangleMesh ball = to_triangle_mesh(test::tessellated_sphere(32, 16).meshes()[0]);
  for (Vec3f& p : ball.positions) p = p * 0.35f + Vec3f{0.2f, 0.9f, -0.3f};
  s.add_mesh(std::move(ball));
  return s;
}

/// `mesh`'s positions moved smoothly: each vertex along a sine of its position (a moderate
/// deformation that keeps neighbours together), scaled by `amount`.
std::vector<Vec3f> wobbled(const MeshView& mesh, float amount) {
  std::vector<Vec3f> p(mesh.positions.begin(), mesh.positions.end());
  for (Vec3f& v : p) v = v + Vec3f{std::sin(4.0f * v.y), std::sin(3.0f * v.z), std::sin(5.0f * v.x)} * amount;
  return p;
}

std::vector<Vec3f> positions_of(const Strided<Vec3f>& p) { return {p.begin(), p.end()}; }

std::vector<Ray> test_rays() {
  std::vector<Ray> rays = test::random_rays(7, 4096);
  const std::vector<Ray> axis = test::axis_rays();
  rays.insert(rays.end(), axis.begin(), axis.end());
  return rays;
}

/// Both queries under both coherence hints, as bytes: equal answers are equal bytes.
std::vector<uint8_t> answers(const Backend& b, const std::vector<Ray>& rays) {
  std::vector<uint8_t> out;
  for (Coherence c : {Coherence::coherent, Coherence::incoherent}) {
    std::vector<Hit> hits(rays.size());
    std::vector<uint8_t> occluded(rays.size());
    b.intersect(rays, hits, c);
    b.occluded(rays, occluded, c);
    const auto* h = reinterpret_cast<const uint8_t*>(hits.data());
    out.insert(out.end(), h, h + hits.size() * sizeof(Hit));
    out.insert(out.end(), occluded.begin(), occluded.end());
  }
  return out;
}

size_t hit_count(const Backend& b, const std::vector<Ray>& rays) {
  std::vector<Hit> hits(rays.size());
  b.intersect(rays, hits, Coherence::coherent);
  size_t n = 0;
  for (const Hit& h : hits) n += h.hit();
  return n;
}

struct Step {
  std::string name;
  std::function<void(Scene&)> change;
};

/// Every kind of change the scene offers, one after another.
std::vector<Step> steps() {
  return {
      {"world mesh vertices", [](Scene& s) { s.set_vertices(3, wobbled(s.meshes()[3], 0.05f)); }},
      {"instanced mesh vertices", [](Scene& s) { s.set_vertices(0, wobbled(s.meshes()[0], 0.1f)); }},
      {"instance transform",
       [](Scene& s) {
         s.set_transform(1, test::placement({0.3f, 0.5f, 0.3f}, {0, 1, 1}, 60.0f, {0.5f, 0.2f, 0.4f}));
       }},
      {"every transform",
       [](Scene& s) {
         for (uint32_t i = 0; i < s.instances().size(); ++i) {
           Affine3f m = s.instances()[i].object_to_world;
           m.m[1][3] += 0.1f * float(i);
           s.set_transform(i, m);
         }
       }},
      {"vertices and a transform",
       [](Scene& s) {
         s.set_vertices(3, wobbled(s.meshes()[3], 0.02f));
         s.set_vertices(1, wobbled(s.meshes()[1], 0.05f));
         s.set_transform(3, test::placement({0.4f, 0.4f, 0.4f}, {1, 0, 0}, 20.0f, {-0.5f, -0.4f, -0.6f}));
       }},
      {"mesh added", [](Scene& s) { s.add_mesh(test::triangle_soup(5, 200).meshes()[0]); }},
      {"instanced mesh added and placed",
       [](Scene& s) {
         const uint32_t m = s.add_instanced_mesh(test::tessellated_sphere(12, 6).meshes()[0]);
         s.add_instance(m, test::placement({0.2f, 0.2f, 0.2f}, {0, 1, 0}, 0.0f, {0.9f, 0.9f, 0.9f}));
       }},
      {"instance removed", [](Scene& s) { s.remove_instance(0); }},
      {"sphere added",
       [](Scene& s) {
         s.add_sphere({{-0.4f, 0.2f, 0.6f}, 0.2f, 0});
       }},
      {"sphere removed", [](Scene& s) { s.remove_sphere(0); }},
      {"quadric removed", [](Scene& s) { s.remove_quadric(0); }},
      {"polygon added",
       [](Scene& s) {
         const std::vector<Vec3f> tri{{-1, 1, 1.2f}, {0, 1, 1.2f}, {-1, 0, 1.3f}};
         s.add_polygon(tri, 0);
       }},
      {"world mesh removed", [](Scene& s) { s.remove_mesh(2); }},
      {"plane added",
       [](Scene& s) {
         s.add_plane({{1.0f, 0.0f, 0.0f}, 1.3f, 0});
       }},
      {"plane removed", [](Scene& s) { s.remove_plane(0); }},
      {"vertices after the changes", [](Scene& s) { s.set_vertices(2, wobbled(s.meshes()[2], 0.03f)); }},
  };
}

TEST(Update, EveryKindOfChangeGivesTheAnswersOfAFreshBuild) {
  const std::vector<Ray> rays = test_rays();
  for (const TraceMethod& v : test::backend_variants()) {
    Scene scene = moving_scene();
    const BackendOptions opts = options(v.variant);
    auto updated = make_backend(v.backend, scene, opts);
    for (const Step& step : steps()) {
      SCOPED_TRACE(v.backend + "/" + v.variant + " after " + step.name);
      step.change(scene);
      EXPECT_FALSE(updated->current());
      updated->update();
      ASSERT_TRUE(updated->current());
      const auto fresh = make_backend(v.backend, scene, opts);
      const std::vector<uint8_t> a = answers(*updated, rays), b = answers(*fresh, rays);
      ASSERT_EQ(a.size(), b.size());
      EXPECT_TRUE(std::memcmp(a.data(), b.data(), a.size()) == 0);
      EXPECT_GT(hit_count(*updated, rays), rays.size() / 8);  // the rays see the scene
    }
  }
}

TEST(Update, TheUpdatedBackendsAgreeWithTheReferenceOfTheChangedScene) {
  // The reference copies the scene: one built from the changed scene is the independent answer.
  const std::vector<Ray> rays = test_rays();
  Scene scene = moving_scene();
  std::vector<std::unique_ptr<Backend>> backends;
  for (const std::string& name : available_backends()) backends.push_back(make_backend(name, scene));
  for (const Step& step : steps()) {
    step.change(scene);
    const Reference ref(scene);
    for (auto& b : backends) {
      SCOPED_TRACE(b->info().name + " after " + step.name);
      b->update();
      std::vector<Hit> hits(rays.size());
      b->intersect(rays, hits, Coherence::incoherent);
      size_t agree = 0;
      for (size_t i = 0; i < rays.size(); ++i) {
        const ReferenceHit r = ref.intersect(rays[i]);
        agree += hits[i].prim_id == r.prim_id && hits[i].instance_id == r.instance_id;
      }
      // Rays through shared edges may take either triangle; every other ray agrees.
      EXPECT_GE(double(agree), 0.995 * double(rays.size()));
    }
  }
}

TEST(Update, AStaleBackendRefusesToTraceAndNamesTheChange) {
  for (const std::string& name : available_backends()) {
    SCOPED_TRACE(name);
    Scene scene = moving_scene();
    auto b = make_backend(name, scene);
    const std::vector<Ray> rays = test_rays();
    std::vector<Hit> hits(rays.size());
    std::vector<uint8_t> occ(rays.size());
    // The case: geometry added after the build; tracing must not answer for the old scene.
    for (int i = 0; i < 100; ++i) scene.add_mesh(test::triangle_soup(uint32_t(i), 1).meshes()[0]);
    scene.add_sphere({{0.0f, 0.0f, 3.0f}, 0.5f, 0});
    const std::string e = test::error_of([&] { b->intersect(rays, hits, Coherence::coherent); });
    EXPECT_NE(e.find("101 changes"), std::string::npos) << e;
    EXPECT_NE(e.find("sphere 1 was added"), std::string::npos) << e;
    EXPECT_NE(e.find("update()"), std::string::npos) << e;
    EXPECT_NE(test::error_of([&] { b->occluded(rays, occ, Coherence::incoherent); }), test::kNoError);
    EXPECT_NE(test::error_of([&] { intersect_parallel(*b, rays, hits, Coherence::coherent); }), test::kNoError);
    b->update();
    EXPECT_EQ(test::error_of([&] { b->intersect(rays, hits, Coherence::coherent); }), test::kNoError);
    scene.set_vertices(3, wobbled(scene.meshes()[3], 0.01f));
    EXPECT_NE(test::error_of([&] { b->intersect(rays, hits, Coherence::incoherent); }).find("mesh 3 has new vertices"),
              std::string::npos);
    scene.set_transform(2, scene.instances()[2].object_to_world);
    EXPECT_NE(
        test::error_of([&] { b->occluded(rays, occ, Coherence::coherent); }).find("instance 2 has a new transform"),
        std::string::npos);
  }
}

TEST(Update, ASharedSceneChangedThroughAnotherHandleIsRefusedUntilUpdated) {
  auto scene = std::make_shared<Scene>(moving_scene());
  auto b = make_backend("simd", std::shared_ptr<const Scene>(scene));
  const std::vector<Ray> rays = test_rays();
  std::vector<Hit> hits(rays.size());
  scene->remove_sphere(0);
  EXPECT_NE(test::error_of([&] { b->intersect(rays, hits, Coherence::coherent); }), test::kNoError);
  b->update();
  const auto fresh = make_backend("simd", *scene);
  EXPECT_EQ(answers(*b, rays), answers(*fresh, rays));
}

TEST(Update, EachChangeDoesTheLeastWork) {
  if (!std::ranges::count(available_backends(), "simd")) GTEST_SKIP() << "simd needs AVX2 and FMA";
  Scene scene = moving_scene();
  auto b = make_backend("simd", scene);
  EXPECT_EQ(b->update().refits + b->update().rebuilds, 0u);  // nothing changed: nothing done
  scene.set_vertices(3, wobbled(scene.meshes()[3], 0.02f));
  UpdateReport r = b->update();
  EXPECT_EQ(r.refits, 1u);  // the world's tree
  EXPECT_EQ(r.rebuilds, 0u);
  EXPECT_FALSE(r.top);
  scene.set_vertices(0, wobbled(scene.meshes()[0], 0.02f));
  r = b->update();
  EXPECT_EQ(r.refits, 1u);  // the instanced mesh's tree, once for its three instances
  EXPECT_EQ(r.rebuilds, 0u);
  EXPECT_TRUE(r.top);  // its instances' boxes moved
  scene.set_transform(4, test::placement({0.3f, 0.3f, 0.3f}, {0, 0, 1}, 10.0f, {0.0f, 0.0f, 0.0f}));
  r = b->update();
  EXPECT_EQ(r.refits + r.rebuilds, 0u);  // the mesh trees stay
  EXPECT_TRUE(r.top);
  scene.add_plane({{0.0f, 1.0f, 0.0f}, 2.0f, 0});
  r = b->update();
  EXPECT_EQ(r.refits + r.rebuilds, 0u);  // planes live beside the trees
  EXPECT_FALSE(r.top);
  scene.add_sphere({{0.0f, 0.0f, 0.0f}, 0.1f, 0});
  r = b->update();
  EXPECT_EQ(r.rebuilds, 1u);  // the world's tree; the mesh trees are kept
  EXPECT_FALSE(r.top);
  const uint32_t m = scene.add_instanced_mesh(test::triangle_soup(3, 50).meshes()[0]);
  scene.add_instance(m, test::placement({0.2f, 0.2f, 0.2f}, {0, 1, 0}, 0.0f, {1.0f, 1.0f, 1.0f}));
  r = b->update();
  EXPECT_EQ(r.rebuilds, 2u);  // the world's (ids moved) and the new mesh's
  EXPECT_TRUE(r.top);
}

TEST(Update, ARefitPastTheLimitIsARebuild) {
  if (!std::ranges::count(available_backends(), "simd")) GTEST_SKIP() << "simd needs AVX2 and FMA";
  // Scrambling the soup's triangles over the box: every leaf's box grows to the whole box.
  Scene scene = test::triangle_soup(11, 2000);
  std::vector<Vec3f> p = positions_of(scene.meshes()[0].positions);
  std::mt19937 rng(3);
  std::shuffle(p.begin(), p.end(), rng);
  const std::vector<Ray> rays = test_rays();
  for (double limit : {1.5, std::numeric_limits<double>::infinity()}) {
    Scene s = scene;
    auto b = make_backend("simd", s, options("default", limit));
    s.set_vertices(0, p);
    const UpdateReport r = b->update();
    EXPECT_EQ(r.rebuilds, std::isinf(limit) ? 0u : 1u) << limit;
    EXPECT_EQ(r.refits, std::isinf(limit) ? 1u : 0u) << limit;
    EXPECT_EQ(answers(*b, rays), answers(*make_backend("simd", s), rays)) << limit;
  }
  EXPECT_NE(test::error_of([&] { make_backend("simd", scene, options("default", 0.5)); }), test::kNoError);
  EXPECT_NE(test::error_of([&] { make_backend("simd", scene, options("default", std::nan(""))); }), test::kNoError);
}

TEST(Update, TrianglesThatGainAreaOrSplitASharedVertexAreFound) {
  // A zero-area triangle is in no leaf; once it has area the tree must hold it. Two vertices
  // at one point share a leaf's vertex slot; moved apart, they cannot.
  TriangleMesh m;
  m.name = "cases";
  m.positions = {{-1, -1, 0},   {1, -1, 0},   {0, 1, 0},     // 0: a triangle
                 {-1, 0, 0.5f}, {1, 0, 0.5f}, {0, 0, 0.5f},  // 1: collinear, zero area
                 {0, 1, 0}};                                 // 6: a copy of vertex 2
  m.indices = {0, 1, 2, 3, 4, 5, 0, 6, 1};
  const std::vector<Ray> rays = test_rays();
  for (const TraceMethod& v : test::backend_variants()) {
    SCOPED_TRACE(v.backend + "/" + v.variant);
    Scene scene;
    scene.add_mesh(m);
    const BackendOptions opts = options(v.variant);
    auto b = make_backend(v.backend, scene, opts);
    std::vector<Vec3f> p = m.positions;
    p[5] = {0, 1, 0.5f};   // triangle 1 has area now
    p[6] = {0, 1, -0.5f};  // vertex 6 leaves vertex 2
    scene.set_vertices(0, p);
    b->update();
    EXPECT_EQ(answers(*b, rays), answers(*make_backend(v.backend, scene, opts), rays));
    const Ray through{{0.0f, 0.5f, 2.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, 10.0f};  // meets triangle 1 first
    Hit h;
    b->intersect(std::span(&through, 1), std::span(&h, 1), Coherence::incoherent);
    EXPECT_EQ(h.prim_id, 1u);
  }
}

TEST(Update, ChangesAreCheckedBeforeAnythingChanges) {
  Scene scene = moving_scene();
  scene.set_transform(0, test::placement({2.0f, 2.0f, 2.0f}, {0, 1, 0}, 0.0f, {0.0f, 0.0f, 0.0f}));
  const Scene before = scene;
  const uint64_t v = scene.version();
  const std::vector<Vec3f> few(3);
  EXPECT_EQ(
      test::error_of([&] { scene.set_vertices(3, few); }),
      "mesh 'uv_sphere' (3): 3 new positions for " + std::to_string(scene.meshes()[3].positions.size()) + " vertices");
  std::vector<Vec3f> far = positions_of(scene.meshes()[3].positions);
  far[7].x = 3e9f;
  EXPECT_NE(test::error_of([&] { scene.set_vertices(3, far); }).find("vertex 7"), std::string::npos);
  far[7].x = std::numeric_limits<float>::quiet_NaN();
  EXPECT_NE(test::error_of([&] { scene.set_vertices(3, far); }).find("non-finite"), std::string::npos);
  // An instanced mesh moved so far that an instance would place it outside the range.
  std::vector<Vec3f> wide = positions_of(scene.meshes()[0].positions);
  wide[0] = {1e9f, 0.0f, 0.0f};  // in range, but twice that once placed
  EXPECT_NE(test::error_of([&] { scene.set_vertices(0, wide); }).find("instance 0 would place it"), std::string::npos);
  Affine3f singular;
  singular.m[0][0] = singular.m[1][1] = singular.m[2][2] = 0.0f;
  EXPECT_NE(test::error_of([&] { scene.set_transform(1, singular); }).find("not invertible"), std::string::npos);
  EXPECT_NE(test::error_of([&] { scene.set_transform(99, Affine3f{}); }).find("out of range"), std::string::npos);
  EXPECT_NE(test::error_of([&] { scene.remove_mesh(0); }).find("placed by instance 0"), std::string::npos);
  EXPECT_NE(test::error_of([&] { scene.remove_sphere(5); }).find("out of range"), std::string::npos);
  EXPECT_EQ(scene.version(), v);  // nothing changed
  EXPECT_EQ(positions_of(scene.meshes()[3].positions), positions_of(before.meshes()[3].positions));
  EXPECT_EQ(positions_of(scene.meshes()[0].positions), positions_of(before.meshes()[0].positions));
  EXPECT_EQ(scene.instances()[0].bounds.hi, before.instances()[0].bounds.hi);
}

TEST(Update, RemovingRenumbersAsDocumented) {
  Scene scene = moving_scene();
  const uint32_t spheres = scene.sphere_base(), tris = scene.triangle_count();
  const uint32_t floor = scene.meshes()[2].triangle_count();
  const uint64_t uid3 = scene.mesh_uid(3);
  scene.remove_mesh(2);
  EXPECT_EQ(scene.triangle_count(), tris - floor);
  EXPECT_EQ(scene.sphere_base(), spheres - floor);
  EXPECT_EQ(scene.mesh_uid(2), uid3);  // the ball moved down, its identity with it
  EXPECT_EQ(scene.mesh_base(2), scene.mesh_base(1) + scene.meshes()[1].triangle_count());
  EXPECT_EQ(scene.locate(scene.mesh_base(2)).shape, 2u);
  const Scene fresh = [] {
    Scene s;
    s.add_polygon(std::vector<Vec3f>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, 0);
    s.add_polygon(std::vector<Vec3f>{{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}}, 0);
    s.remove_polygon(0);
    return s;
  }();
  ASSERT_EQ(fresh.polygons().size(), 1u);
  EXPECT_EQ(fresh.polygons()[0].first, 0u);
  EXPECT_EQ(fresh.polygon_vertices().size(), 4u);
  EXPECT_EQ(fresh.polygon_vertices()[2], (Vec3f{1, 1, 1}));
}

}  // namespace
}  // namespace rp
