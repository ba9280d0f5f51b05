// Meshes in the caller's buffers (Scene::add_shared_mesh): the scene keeps views, not copies;
// every backend and the renderer answer over strided, interleaved buffers exactly as over the
// scene's own copy of the same arrays; the caller's in-place changes reach the backends through
// vertices_changed; bad layouts and the other misuses are refused with a message.

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "backends/registry.h"
#include "render/camera.h"
#include "render/render.h"
#include "tests/support/error_of.h"
#include "tests/support/scenes.h"
#include "tests/support/variants.h"

namespace rp {
namespace {

/// An application's interleaved vertex (32 bytes: Embree shares positions this far apart).
struct Vertex {
  Vec3f position;
  Vec3f normal;
  Vec2f uv;
};
/// An application's face record (16 bytes): the corners, then the material.
struct Face {
  TriangleIndices corners;
  uint32_t material;
};

/// A closed UV sphere in interleaved buffers, with normals, uvs and per-face materials, and a
/// triangle soup in plain arrays (12-byte positions, which Embree copies), that an application
/// owns.
struct Buffers {
  std::vector<Vertex> ball;
  std::vector<Face> ball_faces;
  std::vector<Vec3f> soup;
  std::vector<uint32_t> soup_indices;

  Buffers() {
    const Scene tessellated = test::tessellated_sphere(24, 12);
    const MeshView& sphere = tessellated.meshes()[0];
    for (const Vec3f& p : sphere.positions) ball.push_back({p * 0.5f, p, {0.5f + 0.5f * p.x, 0.5f + 0.5f * p.y}});
    for (uint32_t t = 0; t < sphere.triangle_count(); ++t) ball_faces.push_back({sphere.triangles[t], 1 + t % 2});
    const Scene s = test::triangle_soup(9, 200);
    const TriangleMesh m = to_triangle_mesh(s.meshes()[0]);
    soup = m.positions;
    soup_indices = m.indices;
  }

  MeshView ball_view() const {
    return {.name = "ball",
            .positions = {&ball[0].position, ball.size(), sizeof(Vertex)},
            .triangles = {&ball_faces[0].corners, ball_faces.size(), sizeof(Face)},
            .normals = {&ball[0].normal, ball.size(), sizeof(Vertex)},
            .uvs = {&ball[0].uv, ball.size(), sizeof(Vertex)},
            .face_materials = {&ball_faces[0].material, ball_faces.size(), sizeof(Face)},
            .material = 0};
  }
  MeshView soup_view() const {
    return {.name = "soup",
            .positions = soup,
            .triangles = {reinterpret_cast<const TriangleIndices*>(soup_indices.data()), soup_indices.size() / 3},
            .normals = {},
            .uvs = {},
            .face_materials = {},
            .material = 0};
  }
};

/// The same scene over the buffers (shared) or over the scene's copies of them: the ball as a
/// world mesh, the soup placed twice by instances, a sphere and a plane beside them.
Scene scene_of(const Buffers& b, bool shared) {
  Scene s;
  s.add_material({.name = "red", .diffuse = {0.8f, 0.1f, 0.1f}});
  s.add_material({.name = "mirror", .diffuse = Vec3f(0.2f), .mirror = 0.6f});
  if (shared) {
    s.add_shared_mesh(b.ball_view());
    s.add_shared_instanced_mesh(b.soup_view());
  } else {
    s.add_mesh(b.ball_view());
    s.add_instanced_mesh(b.soup_view());
  }
  s.add_instance(1, test::placement({0.5f, 0.5f, 0.5f}, {0, 1, 0}, 30.0f, {-0.9f, 0.2f, 0.1f}));
  s.add_instance(1, test::placement({-0.4f, 0.4f, 0.4f}, {1, 0, 0}, 60.0f, {0.9f, -0.3f, 0.2f}));  // mirrored
  s.add_sphere({{0.0f, 1.1f, 0.3f}, 0.25f, 1});
  s.add_plane({{0.0f, 1.0f, 0.0f}, 1.3f, 0});
  s.add_light(PointLight{{2.0f, 3.0f, 4.0f}, Vec3f{20.0f}});
  s.set_camera({{0.3f, 0.6f, 3.5f}, {0, 0, 0}, {0, 1, 0}, 50.0f});
  return s;
}

std::vector<Ray> rays() {
  std::vector<Ray> r = test::random_rays(5, 4096);
  const std::vector<Ray> axis = test::axis_rays();
  r.insert(r.end(), axis.begin(), axis.end());
  return r;
}

/// Closest hits and occlusion under both coherence hints, every hit, and closest points from
/// a grid, as bytes: equal answers are equal bytes.
std::vector<uint8_t> answers(const Backend& b, const std::vector<Ray>& rs) {
  std::vector<uint8_t> out;
  auto put = [&](const auto& v) {
    const auto* p = reinterpret_cast<const uint8_t*>(v.data());
    out.insert(out.end(), p, p + v.size() * sizeof(v[0]));
  };
  for (Coherence c : {Coherence::coherent, Coherence::incoherent}) {
    std::vector<Hit> hits(rs.size());
    std::vector<uint8_t> occluded(rs.size());
    b.intersect(rs, hits, c);
    b.occluded(rs, occluded, c);
    put(hits);
    put(occluded);
  }
  put(b.all_hits(rs).hits);
  std::vector<PointQuery> q;
  for (int i = 0; i < 512; ++i)
    q.push_back({{-1.2f + 0.3f * float(i % 9), -1.1f + 0.25f * float(i / 9 % 9), -1.0f + 0.4f * float(i / 81)}});
  std::vector<ClosestPoint> cp(q.size());
  b.closest_points(q, cp);
  put(cp);
  return out;
}

TEST(SharedMesh, TheSceneViewsTheCallersBuffersWithoutACopy) {
  const Buffers b;
  const Scene shared = scene_of(b, true), owned = scene_of(b, false);
  EXPECT_TRUE(shared.is_shared(0) && shared.is_shared(1));
  EXPECT_FALSE(owned.is_shared(0) || owned.is_shared(1));
  EXPECT_EQ(static_cast<const void*>(shared.meshes()[0].positions.data()), static_cast<const void*>(&b.ball[0]));
  EXPECT_EQ(static_cast<const void*>(shared.meshes()[1].triangles.data()),
            static_cast<const void*>(b.soup_indices.data()));
  EXPECT_EQ(shared.meshes()[0].positions.stride(), sizeof(Vertex));
  // The owned copy holds the arrays; the shared scene holds none of them.
  const size_t arrays =
      b.ball.size() * (12 + 12 + 8) + b.ball_faces.size() * 16 + b.soup.size() * 12 + b.soup_indices.size() * 4;
  EXPECT_EQ(owned.bytes() - shared.bytes(), arrays);
}

TEST(SharedMesh, EveryBackendAnswersAsOverTheScenesOwnCopy) {
  const Buffers b;
  const Scene shared = scene_of(b, true), owned = scene_of(b, false);
  const std::vector<Ray> rs = rays();
  for (const TraceMethod& v : test::backend_variants()) {
    SCOPED_TRACE(v.backend + "/" + v.variant);
    BackendOptions o;
    o.variant = v.variant;
    const std::vector<uint8_t> a = answers(*make_backend(v.backend, shared, o), rs);
    const std::vector<uint8_t> c = answers(*make_backend(v.backend, owned, o), rs);
    ASSERT_EQ(a.size(), c.size());
    EXPECT_TRUE(std::memcmp(a.data(), c.data(), a.size()) == 0);
    std::vector<Hit> hits(rs.size());
    make_backend(v.backend, shared, o)->intersect(rs, hits, Coherence::incoherent);
    size_t on_ball = 0;
    for (const Hit& h : hits) on_ball += h.prim_id < shared.meshes()[0].triangle_count();
    EXPECT_GT(on_ball, rs.size() / 20);  // the rays see the shared mesh
  }
}

TEST(SharedMesh, TheRendererShadesStridedNormalsUvsAndMaterialsAsTheCopys) {
  const Buffers b;
  const Scene shared = scene_of(b, true), owned = scene_of(b, false);
  RenderSettings st;
  st.width = 96;
  st.height = 72;
  st.spp = 2;
  const Camera cam(*shared.camera(), st.width, st.height);
  for (const std::string& name : available_backends()) {
    SCOPED_TRACE(name);
    const Image x = render(shared, *make_backend(name, shared), cam, st).image;
    const Image y = render(owned, *make_backend(name, owned), cam, st).image;
    EXPECT_EQ(x.rgb, y.rgb);
    // Both materials of the faces show: the face material view is read.
    size_t red = 0;
    for (size_t p = 0; p < x.rgb.size() / 3; ++p) red += x.rgb[3 * p] > 2.0f * x.rgb[3 * p + 1] + 0.02f;
    EXPECT_GT(red, size_t(20));
  }
}

TEST(SharedMesh, InPlaceChangesReachTheBackendsThroughVerticesChanged) {
  Buffers b;
  Scene shared = scene_of(b, true);
  const std::vector<Ray> rs = rays();
  std::vector<std::unique_ptr<Backend>> backends;
  std::vector<BackendOptions> opts;
  for (const TraceMethod& v : test::backend_variants()) {
    BackendOptions o;
    o.variant = v.variant;
    backends.push_back(make_backend(v.backend, shared, o));
    opts.push_back(o);
  }
  // The application moves its vertices (and normals) in place: the ball and the soup.
  for (Vertex& v : b.ball) v.position = v.position * 1.3f + Vec3f{0.1f, -0.2f, 0.05f};
  for (Vec3f& p : b.soup) p = p + Vec3f{std::sin(5.0f * p.y), 0.0f, std::cos(3.0f * p.x)} * 0.1f;
  shared.vertices_changed(0);
  shared.vertices_changed(1);
  const Scene owned = scene_of(b, false);  // a copy of the moved arrays: the independent answer
  EXPECT_EQ(shared.mesh_bounds(0).hi.x, owned.mesh_bounds(0).hi.x);
  EXPECT_EQ(shared.instances()[0].bounds.lo.y, owned.instances()[0].bounds.lo.y);
  const std::vector<TraceMethod> variants = test::backend_variants();
  for (size_t i = 0; i < backends.size(); ++i) {
    SCOPED_TRACE(variants[i].backend + "/" + variants[i].variant);
    EXPECT_FALSE(backends[i]->current());
    backends[i]->update();
    const std::vector<uint8_t> a = answers(*backends[i], rs);
    const std::vector<uint8_t> c = answers(*make_backend(variants[i].backend, owned, opts[i]), rs);
    ASSERT_EQ(a.size(), c.size());
    EXPECT_TRUE(std::memcmp(a.data(), c.data(), a.size()) == 0);
  }
}

TEST(SharedMesh, ACopyOfTheSceneOwnsCopiesOfItsOwnArraysAndSharesTheCallers) {
  const Buffers b;
  const std::vector<Ray> rs = rays();
  auto original = std::make_unique<Scene>(scene_of(b, false));
  original->add_shared_mesh(b.ball_view());
  const Scene copy = *original;
  EXPECT_NE(static_cast<const void*>(copy.meshes()[0].positions.data()),
            static_cast<const void*>(original->meshes()[0].positions.data()));
  EXPECT_EQ(static_cast<const void*>(copy.meshes()[2].positions.data()), static_cast<const void*>(&b.ball[0]));
  Scene assigned;
  assigned = *original;
  const std::vector<uint8_t> before = answers(*make_backend(available_backends()[0], *original), rs);
  original.reset();  // the copies' views must not point into it
  EXPECT_TRUE(before == answers(*make_backend(available_backends()[0], copy), rs));
  EXPECT_TRUE(before == answers(*make_backend(available_backends()[0], assigned), rs));
}

TEST(SharedMesh, BadLayoutsAndMisusesAreRefusedWithAMessage) {
  Buffers b;
  Scene s;
  s.add_material({.name = "red"});
  s.add_material({.name = "blue"});
  MeshView v = b.ball_view();
  v.positions = {reinterpret_cast<const Vec3f*>(reinterpret_cast<const char*>(&b.ball[0].position) + 2), b.ball.size(),
                 sizeof(Vertex)};
  EXPECT_NE(test::error_of([&] { s.add_shared_mesh(v); }).find("mesh 'ball': the positions buffer"), std::string::npos);
  v = b.ball_view();
  v.positions = {&b.ball[0].position, b.ball.size(), 10};
  EXPECT_NE(test::error_of([&] { s.add_shared_mesh(v); }).find("a stride of at least 12"), std::string::npos);
  v = b.ball_view();
  v.triangles = {nullptr, 4, sizeof(Face)};
  EXPECT_NE(test::error_of([&] { s.add_shared_mesh(v); }).find("the triangles buffer"), std::string::npos);
  b.ball_faces[5].corners[1] = uint32_t(b.ball.size());
  EXPECT_EQ(
      test::error_of([&] { s.add_shared_mesh(b.ball_view()); }),
      "mesh 'ball': triangle 5 uses vertex " + std::to_string(b.ball.size()) + " of " + std::to_string(b.ball.size()));
  b.ball_faces[5].corners[1] = 0;
  v = b.ball_view();
  v.normals = {&b.ball[0].normal, b.ball.size() - 1, sizeof(Vertex)};
  EXPECT_NE(test::error_of([&] { s.add_shared_mesh(v); }).find("normals for"), std::string::npos);
  EXPECT_EQ(s.meshes().size(), 0u);  // nothing was added by the refused calls
  const uint32_t m = s.add_shared_mesh(b.ball_view());
  const std::vector<Vec3f> same(s.meshes()[m].positions.begin(), s.meshes()[m].positions.end());
  EXPECT_NE(test::error_of([&] { s.set_vertices(m, same); }).find("vertices_changed"), std::string::npos);
  const uint32_t own = s.add_mesh(b.soup_view());
  EXPECT_NE(test::error_of([&] { s.vertices_changed(own); }).find("set_vertices"), std::string::npos);
  // A bad vertex written in place is refused and the version stays: no backend updates to it.
  const uint64_t version = s.version();
  b.ball[7].position.y = std::nanf("");
  EXPECT_EQ(test::error_of([&] { s.vertices_changed(m); }), "mesh 'ball' (0): vertex 7 has a non-finite coordinate");
  EXPECT_EQ(s.version(), version);
}

}  // namespace
}  // namespace rp
