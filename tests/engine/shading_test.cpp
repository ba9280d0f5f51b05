// The renderer's 8-wide per-hit work against its scalar twin, bit for bit: shade_batch8 against
// shade_batch_scalar on random hits of a scene with every kind of primitive and light and
// material (meshes with and without vertex normals and per-face materials, a degenerate
// triangle, analytic primitives, planes, misses, rays with no path, batch lengths that are
// not multiples of 8), and Camera::generate_rays against generate for every camera model. Both
// 8-wide routines run only on a CPU with AVX2 and FMA; elsewhere these tests say so and skip.

#include <gtest/gtest.h>

#include <bit>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "render/camera.h"
#include "render/shade_group.h"
#include "tests/support/scenes.h"

namespace rp {
namespace {

bool cpu_has_avx2_fma() { return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"); }

uint32_t bits(float f) { return std::bit_cast<uint32_t>(f); }
bool same(const Vec3f& a, const Vec3f& b) { return bits(a.x) == bits(b.x) && bits(a.y) == bits(b.y) && bits(a.z) == bits(b.z); }
std::string show(const Vec3f& v) { return std::to_string(v.x) + " " + std::to_string(v.y) + " " + std::to_string(v.z); }

/// Every kind of primitive, material and light the shading handles.
Scene shading_scene() {
  Scene s = test::analytic_scene();
  const uint32_t shiny = s.add_material({.name = "shiny", .diffuse = {0.7f, 0.2f, 0.1f}, .specular = {0.5f, 0.4f, 0.3f},
                                         .shininess = 48.0f});
  const uint32_t mirror = s.add_material({.name = "mirror", .specular = {0.9f, 0.9f, 0.9f}, .mirror = 0.8f});
  const uint32_t glass = s.add_material({.name = "glass", .specular = {1.0f, 1.0f, 1.0f}, .ior = 1.5f, .opacity = 0.1f});
  const uint32_t glow = s.add_material({.name = "glow", .diffuse = {0.2f, 0.2f, 0.2f}, .shininess = 0.0f,
                                        .emission = {2.0f, 1.0f, 0.5f}});
  std::mt19937 rng(7);
  for (int mesh = 0; mesh < 3; ++mesh) {
    TriangleMesh m;
    m.name = "mesh" + std::to_string(mesh);
    for (int v = 0; v < 60; ++v) m.positions.push_back(test::random_in_box(rng, -2.0f, 2.0f));
    for (int t = 0; t < 40; ++t)
      for (int k = 0; k < 3; ++k) m.indices.push_back(uint32_t(rng() % 60));
    // A degenerate triangle (three times one vertex): its normal has no direction.
    m.indices.insert(m.indices.end(), {5, 5, 5});
    if (mesh != 1) {  // vertex normals, one of them zero
      for (int v = 0; v < 60; ++v) m.normals.push_back(v == 3 ? Vec3f{} : test::random_direction(rng));
    }
    m.material = mesh == 0 ? shiny : 0;
    if (mesh == 2) {
      const uint32_t choice[5] = {0, shiny, mirror, glass, glow};
      for (uint32_t t = 0; t < m.triangle_count(); ++t) m.face_materials.push_back(choice[rng() % 5]);
    }
    s.add_mesh(std::move(m));
  }
  // A polygon and a sphere with materials of their own (the analytic scene's use material 0).
  const Vec3f corners[3] = {{-1.5f, 2.0f, 0.5f}, {1.5f, 2.2f, 0.4f}, {0.0f, 2.5f, -1.0f}};
  s.add_polygon(corners, shiny);
  s.add_sphere({{0.5f, -0.5f, 1.5f}, 0.25f, glow});
  // An instanced mesh (vertex normals, per-face materials) placed three times, one mirrored.
  TriangleMesh placed;
  placed.name = "placed";
  for (int v = 0; v < 30; ++v) {
    placed.positions.push_back(test::random_in_box(rng, -1.0f, 1.0f));
    placed.normals.push_back(test::random_direction(rng));
  }
  for (int t = 0; t < 20; ++t) {
    for (int k = 0; k < 3; ++k) placed.indices.push_back(uint32_t(rng() % 30));
    placed.face_materials.push_back(t % 2 ? shiny : glass);
  }
  const uint32_t p = s.add_instanced_mesh(std::move(placed));
  s.add_instance(p, test::placement({1.0f, 1.0f, 1.0f}, {0, 1, 0}, 30.0f, {1.0f, 0.5f, 0.0f}));
  s.add_instance(p, test::placement({0.5f, 2.0f, 1.0f}, {1, 0, 1}, 70.0f, {-1.0f, 0.0f, 1.0f}));
  s.add_instance(p, test::placement({-1.0f, 1.0f, 1.0f}, {0, 0, 1}, 0.0f, {0.0f, -1.0f, -1.0f}));
  s.add_light(PointLight{{3.0f, 4.0f, 2.0f}, {20.0f, 18.0f, 15.0f}});
  s.add_light(PointLight{{-2.0f, 1.0f, -3.0f}, {5.0f, 5.0f, 8.0f}});
  s.add_light(DirectionalLight{normalize(Vec3f{-0.3f, -1.0f, 0.2f}), {0.8f, 0.8f, 0.7f}});
  return s;
}

struct Batch {
  std::vector<Ray> rays;
  std::vector<Hit> hits;
  std::vector<PathState> paths;
};

/// `n` random rays with hits drawn on random primitives (the shading reads the hit, not the
/// geometry behind it), grouped so that some groups of 8 hit one triangle, some one mesh, some
/// several, some an analytic primitive, some an instanced mesh through its instances; misses
/// and rays without a path mixed in. A hit on an instanced mesh's triangle names one of its
/// instances.
Batch random_batch(const Scene& s, std::mt19937& rng, size_t n) {
  Batch b;
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  const uint32_t mesh_begin = s.mesh_base(1), mesh_end = mesh_begin + s.meshes()[1].triangle_count();
  uint32_t group_triangle = 0;  // the one triangle of a group that hits one
  for (size_t i = 0; i < n; ++i) {
    const size_t group = i / 8;
    if (i % 8 == 0) group_triangle = uint32_t(rng() % s.triangle_count());
    Ray r{test::random_in_box(rng, -3.0f, 3.0f), 0.0f, test::random_direction(rng) * (0.5f + 2.0f * u01(rng)),
          std::numeric_limits<float>::infinity()};
    uint32_t prim;
    const uint32_t placed = uint32_t(s.meshes().size() - 1);
    switch (group % 6) {
      case 0: prim = mesh_begin + uint32_t(rng() % (mesh_end - mesh_begin)); break;  // one mesh
      case 1: prim = uint32_t(rng() % s.triangle_count()); break;                    // any mesh
      case 2: prim = s.mesh_base(placed) + uint32_t(rng() % s.meshes()[placed].triangle_count()); break;
      case 3:
        prim = group_triangle;
        break;                                                                        // one triangle
      default: prim = uint32_t(rng() % s.prim_count()); break;                        // any primitive
    }
    float u = u01(rng), v = u01(rng);
    if (u + v > 1.0f) u = 1.0f - u, v = 1.0f - v;
    Hit h{0.2f + 4.0f * u01(rng), prim, u, v};
    if (prim >= s.mesh_base(placed) && prim < s.triangle_count()) h.instance_id = uint32_t(rng() % s.instances().size());
    if (rng() % 10 == 0) h = Hit{};  // a miss
    PathState p{uint32_t(i), {u01(rng), u01(rng), u01(rng)}};
    if (rng() % 17 == 0) p.slot = kInvalidId;  // no path
    b.rays.push_back(r);
    b.hits.push_back(h);
    b.paths.push_back(p);
  }
  return b;
}

struct Shaded {
  std::vector<Vec3f> colour;
  std::vector<std::vector<Ray>> shadow;
  std::vector<std::vector<Pending>> pending;
  std::vector<BounceHit> bounces;
};

/// The shading of batch b by fn, the queues' records copied out (only this batch's).
Shaded shade(ShadeBatchFn fn, const ShadeScene& s, const Batch& b, bool bounce) {
  Shaded out;
  out.colour.assign(b.rays.size(), Vec3f{0.25f});
  std::vector<ShadowQueue> queues(s.shadow_tfar.size());
  for (ShadowQueue& q : queues) q.reset(b.rays.size());
  ShadeOut sink{out.colour, queues, out.bounces};
  fn(s, b.rays, b.hits, b.paths, bounce, sink);
  for (const ShadowQueue& q : queues) {
    out.shadow.emplace_back(q.batch_rays().begin(), q.batch_rays().end());
    out.pending.emplace_back(q.batch_pending().begin(), q.batch_pending().end());
  }
  return out;
}

TEST(ShadeBatch8, GivesTheScalarShadingsBitsForEveryRay) {
  if (!cpu_has_avx2_fma()) GTEST_SKIP() << "this CPU lacks AVX2 or FMA: the 8-wide shading is not used here";
  const Scene scene = shading_scene();
  const ShadeScene s(scene);
  std::mt19937 rng(11);
  size_t rays = 0, shadow_rays = 0, bounces = 0;
  for (const size_t n : {size_t(1), size_t(7), size_t(8), size_t(9), size_t(64), size_t(257), size_t(2048)})
    for (const bool bounce : {false, true}) {
      const Batch b = random_batch(scene, rng, n);
      const Shaded want = shade(shade_batch_scalar, s, b, bounce), got = shade(shade_batch8, s, b, bounce);
      rays += n;
      for (size_t i = 0; i < n; ++i)
        ASSERT_TRUE(same(got.colour[i], want.colour[i])) << "colour of ray " << i << " of " << n << ": "
                                                         << show(got.colour[i]) << " / " << show(want.colour[i]);
      for (size_t l = 0; l < want.shadow.size(); ++l) {
        ASSERT_EQ(got.shadow[l].size(), want.shadow[l].size()) << "light " << l;
        ASSERT_EQ(got.pending[l].size(), want.pending[l].size()) << "light " << l;
        shadow_rays += want.shadow[l].size();
        for (size_t k = 0; k < want.shadow[l].size(); ++k) {
          ASSERT_EQ(std::memcmp(&got.shadow[l][k], &want.shadow[l][k], sizeof(Ray)), 0) << "shadow ray " << k << " of light " << l;
          ASSERT_EQ(got.pending[l][k].slot, want.pending[l][k].slot);
          ASSERT_TRUE(same(got.pending[l][k].contribution, want.pending[l][k].contribution)) << "light " << l << " " << k;
        }
      }
      ASSERT_EQ(got.bounces.size(), want.bounces.size());
      bounces += want.bounces.size();
      for (size_t k = 0; k < want.bounces.size(); ++k) {
        const BounceHit &g = got.bounces[k], &w = want.bounces[k];
        ASSERT_EQ(g.ray, w.ray);
        ASSERT_TRUE(same(g.position, w.position) && same(g.ng, w.ng) && same(g.d, w.d) && same(g.origin, w.origin));
        ASSERT_EQ(g.back, w.back);
        ASSERT_EQ(g.material, w.material);
      }
    }
  // The comparison covered real work, not only misses.
  EXPECT_GT(shadow_rays, rays / 2);
  EXPECT_GT(bounces, size_t(100));
}

/// Every model's rays from generate_rays equal generate's bit for bit, for batches of every
/// length from 0 to 40 (pinhole rays go 8 at a time, the last n % 8 one at a time).
TEST(Camera, GenerateRaysGivesGeneratesRaysForEveryModel) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  for (const CameraModel model : {CameraModel::pinhole, CameraModel::panoramic, CameraModel::fisheye, CameraModel::thin_lens}) {
    CameraDesc d{{0.3f, 1.2f, 4.0f}, {0.0f, 0.5f, 0.0f}, {0.0f, 1.0f, 0.0f}, 50.0f};
    d.model = model;
    d.aperture = 0.1f;
    const Camera cam(d, 320, 200);
    for (int round = 0; round < 100; ++round) {
      const size_t n = size_t(round % 41);
      std::vector<float> px(n), py(n);
      std::vector<Vec2f> lens(n);
      for (size_t i = 0; i < n; ++i) {
        px[i] = u01(rng) * 320.0f;
        py[i] = u01(rng) * 200.0f;
        lens[i] = {u01(rng), u01(rng)};
      }
      std::vector<Ray> got(n);
      cam.generate_rays(px, py, lens.data(), got);
      for (size_t i = 0; i < n; ++i) {
        const Ray want = cam.generate(px[i], py[i], lens[i]);
        ASSERT_EQ(std::memcmp(&got[i], &want, sizeof(Ray)), 0) << "model " << int(model) << " ray " << i << " of " << n;
      }
    }
  }
}

}  // namespace
}  // namespace rp
