// The simd backend's four traversals give every ray the same answer, bit for bit: large
// packets and independent 8-ray packets (coherent spans), ray streams (incoherent batches),
// and single rays, the reference — for every variant, on spans that split and recombine
// packets and streams (octant changes, tnear > 0, finite tfar, invalid rays inside a span,
// direction components of 0 and below 2^-128, lengths that are not multiples of 8, single
// rays, spans longer than a large packet) and on rays aimed at shared edges and vertices.
//
// Exact ties (two primitives at the same t) go to the lower prim_id on every path. The one
// allowed difference is a near-tie: both answers are hits of their primitive's own test and
// their t differ by at most 1e-6 relative (the diff tool's tie class). There the Möller–Trumbore
// test can report a triangle hit a rounding error in front of the triangle's own box (a ray
// through a shared edge), which a traversal finds or prunes depending on the order it meets
// the leaves; such rays are counted and must stay rare.

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cstdio>
#include <tuple>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "analysis/raygen.h"
#include "backends/registry.h"
#include "core/affine.h"
#include "core/geometry/triangle.h"
#include "core/scene.h"
#include "tests/support/scenes.h"

namespace rp {
namespace {

using test::analytic_scene;
using test::random_direction;
using test::random_in_box;
using test::random_rays;
using test::tessellated_sphere;
using test::triangle_soup;

/// The ways one variant traces a batch: `large` traces coherent spans by large packets and
/// incoherent ones as ray streams, `packet8` coherent spans by 8-ray packets, `single`
/// incoherent ones ray by ray.
struct Paths {
  std::unique_ptr<Backend> large, packet8, single;
};

Paths make_paths(const Scene& scene, const std::string& variant) {
  return {make_backend("simd", scene, {.variant = variant, .device_config = {}, .coherent_method = "large", .incoherent_method = "stream"}),
          make_backend("simd", scene, {.variant = variant, .device_config = {}, .coherent_method = "packet8", .incoherent_method = {}}),
          make_backend("simd", scene, {.variant = variant, .device_config = {}, .coherent_method = {}, .incoherent_method = "single"})};
}

uint32_t bits(float f) { return std::bit_cast<uint32_t>(f); }

/// True when hit h of ray r is a hit of its primitive's own scalar test (a triangle's, by the
/// variant's test, in its instance's object space for an instance's hit, or an analytic
/// primitive's).
bool own_test_hits(const Scene& s, const Ray& world, const Hit& h, bool watertight) {
  const PrimLocation ref = s.locate(h.prim_id);
  if (ref.kind != PrimKind::triangle) return true;
  const Ray r = h.instance_id == kNoInstance ? world : object_ray(world, s.instances()[h.instance_id].world_to_object);
  const MeshView& m = s.meshes()[ref.shape];
  const Vec3f a = m.vertex(ref.local, 0), b = m.vertex(ref.local, 1), c = m.vertex(ref.local, 2);
  return (watertight ? intersect_triangle_watertight(r, a, b, c) : intersect_triangle_mt_normal(r, a, b, c)).hit;
}

/// Traces `rays` by large packets and ray streams (batches of `span` rays), 8-ray packets and
/// single rays, and checks every answer is the same, closest and any hit (near-ties excepted
/// and counted in `near_ties`; see the top of this file). Returns the number of hits.
int expect_same_answers(const Scene& scene, const Paths& paths, const std::vector<Ray>& rays, size_t span,
                        const std::string& what, int& near_ties, bool watertight) {
  const size_t n = rays.size();
  std::vector<Hit> large(n), packet8(n), stream(n), single(n);
  std::vector<uint8_t> occ_large(n), occ_packet8(n), occ_stream(n), occ_single(n);
  for (size_t base = 0; base < n; base += span) {
    const size_t m = std::min(span, n - base);
    const std::span<const Ray> r = std::span<const Ray>(rays).subspan(base, m);
    paths.large->intersect(r, std::span<Hit>(large).subspan(base, m), Coherence::coherent);
    paths.large->occluded(r, std::span<uint8_t>(occ_large).subspan(base, m), Coherence::coherent);
    paths.large->intersect(r, std::span<Hit>(stream).subspan(base, m), Coherence::incoherent);
    paths.large->occluded(r, std::span<uint8_t>(occ_stream).subspan(base, m), Coherence::incoherent);
  }
  paths.packet8->intersect(rays, packet8, Coherence::coherent);
  paths.packet8->occluded(rays, occ_packet8, Coherence::coherent);
  paths.single->intersect(rays, single, Coherence::incoherent);
  paths.single->occluded(rays, occ_single, Coherence::incoherent);
  int hits = 0, failures = 0;
  for (size_t i = 0; i < n && failures < 10; ++i) {
    hits += single[i].hit();
    for (const auto& [name, h, occ] : {std::tuple{"large", large[i], occ_large[i]}, std::tuple{"packet8", packet8[i], occ_packet8[i]},
                                       std::tuple{"stream", stream[i], occ_stream[i]}}) {
      const bool same = h.prim_id == single[i].prim_id && h.instance_id == single[i].instance_id &&
                        bits(h.t) == bits(single[i].t) && bits(h.u) == bits(single[i].u) &&
                        bits(h.v) == bits(single[i].v) && occ == occ_single[i];
      if (same) continue;
      const bool near_tie = h.hit() && single[i].hit() && occ == occ_single[i] &&
                            std::abs(double(h.t) - double(single[i].t)) <= 1e-6 * std::max(double(h.t), double(single[i].t)) &&
                            own_test_hits(scene, rays[i], h, watertight) &&
                            own_test_hits(scene, rays[i], single[i], watertight);
      if (near_tie) {
        ++near_ties;
        continue;
      }
      ++failures;
      ADD_FAILURE() << what << " ray " << i << ": " << name << " prim " << h.prim_id << " instance " << h.instance_id
                    << " t " << h.t << " u " << h.u << " v " << h.v << " occluded " << int(occ) << "; single prim "
                    << single[i].prim_id << " instance " << single[i].instance_id << " t " << single[i].t << " u "
                    << single[i].u << " v " << single[i].v << " occluded " << int(occ_single[i]);
    }
  }
  return hits;
}

/// Rays from `eye` at the vertices and edge midpoints of the tessellated sphere (where two,
/// and at vertices several, triangles give the same t), in spans of neighbouring targets, some
/// nudged by an ulp or two; the sphere placed by `placement` (its vertices mapped in double).
std::vector<Ray> shared_edge_rays(const Scene& s, const Vec3f& eye, uint32_t seed, const Affine3f& placement = {}) {
  std::mt19937 rng(seed);
  std::vector<Ray> rays;
  const MeshView& m = s.meshes()[0];
  const Affine3d to_world(placement);
  const auto vertex = [&](uint32_t t, int k) { return Vec3f(to_world.point(Vec3d(m.vertex(t, k)))); };
  for (uint32_t t = 0; t < m.triangle_count(); ++t)
    for (int k = 0; k < 3; ++k) {
      const Vec3f a = vertex(t, k), b = vertex(t, (k + 1) % 3);
      for (const Vec3f& target : {a, (a + b) * 0.5f}) {
        Vec3f d = target - eye;
        if (rng() % 4 == 0) d.x = std::nextafter(d.x, rng() % 2 ? 1.0f : -1.0f);
        rays.push_back({eye, 0.0f, d, std::numeric_limits<float>::infinity()});
      }
    }
  return rays;
}

class PacketPaths : public ::testing::TestWithParam<std::string> {
 protected:
  void SetUp() override {
    bool simd = false;
    for (const BackendEntry& e : list_backends()) simd = simd || (e.name == "simd" && e.available);
    if (!simd) GTEST_SKIP() << "the simd backend is not available on this CPU (AVX2 and FMA)";
  }
};

TEST_P(PacketPaths, CameraTilesGiveTheSameAnswersOnEveryPath) {
  const Scene scene = make_default_scene();
  const Paths paths = make_paths(scene, GetParam());
  const RaySet primary = primary_rays(scene, 96, 64);
  int near_ties = 0;
  for (size_t span : {size_t(256), size_t(512), size_t(4096), size_t(40), size_t(1)})
    EXPECT_GT(expect_same_answers(scene, paths, primary.rays, span, "camera tiles, span " + std::to_string(span),
                                  near_ties, GetParam() == "watertight"),
              2000);
  EXPECT_EQ(near_ties, 0);
}

TEST_P(PacketPaths, SharedEdgesAndVerticesGiveTheSameAnswersOnEveryPath) {
  const Scene scene = tessellated_sphere(24, 12);
  const Paths paths = make_paths(scene, GetParam());
  int near_ties = 0, rays_traced = 0;
  for (const Vec3f& eye : {Vec3f{0.1f, 0.2f, 5.0f}, Vec3f{-3.0f, 2.5f, 2.0f}, Vec3f{0.0f, 0.0f, -4.0f}}) {
    const std::vector<Ray> rays = shared_edge_rays(scene, eye, 5);
    for (size_t span : {size_t(256), size_t(64), size_t(9)}) {
      EXPECT_GT(expect_same_answers(scene, paths, rays, span, "shared edges, span " + std::to_string(span), near_ties,
                                    GetParam() == "watertight"),
                500);
      rays_traced += int(rays.size());
    }
  }
  // A near-tie is counted once per path that differs; at most 0.5% of the rays on each path.
  EXPECT_LE(near_ties, 3 * rays_traced / 200) << near_ties << " near-ties in " << rays_traced << " rays x 3 paths";
  std::printf("shared edges (%s): %d near-ties in %d rays x 3 paths\n", GetParam().c_str(), near_ties, rays_traced);
}

TEST_P(PacketPaths, MixedSpansSplitAndRecombineWithTheSameAnswers) {
  // Spans mixing every direction octant, tnear > 0, finite tfar, axis-parallel directions
  // (a zero component: no octant beam), components whose inverse overflows, and invalid rays.
  Scene scene = triangle_soup(3, 4000);
  scene.add_sphere({{0.3f, -0.2f, 0.1f}, 0.4f, 0});
  scene.add_plane({{0.0f, 1.0f, 0.0f}, 1.2f, 0});
  const Paths paths = make_paths(scene, GetParam());
  std::vector<Ray> rays = random_rays(17, 6000);
  std::mt19937 rng(23);
  for (size_t i = 0; i < rays.size(); ++i) {
    if (i % 97 == 0) rays[i].org.x = std::numeric_limits<float>::quiet_NaN();
    if (i % 89 == 0) rays[i].dir = Vec3f{0.0f, -1.0f, 0.0f};
    if (i % 79 == 0) rays[i].dir.z = 0x1p-140f;  // its inverse overflows: the exact slab form
    if (i % 83 == 0) rays[i].tnear = rays[i].tfar + 1.0f;
    if (i % 101 == 0) rays[i].org.x = 2e9f;      // beyond the coordinate range (invalid), yet it would meet the plane
    if (i % 7 == 0) rays[i].dir = -rays[i].dir;  // another octant inside a coherent group
  }
  int near_ties = 0;
  for (size_t span : {size_t(6000), size_t(512), size_t(256), size_t(100), size_t(8), size_t(3), size_t(1)})
    EXPECT_GT(expect_same_answers(scene, paths, rays, span, "mixed, span " + std::to_string(span), near_ties,
                                  GetParam() == "watertight"),
              1000);
  EXPECT_EQ(near_ties, 0);
}

TEST_P(PacketPaths, AnalyticPrimitivesGiveTheSameAnswersOnEveryPath) {
  const Scene scene = analytic_scene();
  const Paths paths = make_paths(scene, GetParam());
  const std::vector<Ray> rays = random_rays(29, 4000);
  int near_ties = 0;
  for (size_t span : {size_t(512), size_t(24)})
    EXPECT_GT(expect_same_answers(scene, paths, rays, span, "analytic, span " + std::to_string(span), near_ties, false),
              1000);
  EXPECT_EQ(near_ties, 0);
}

TEST_P(PacketPaths, InstancesGiveTheSameAnswersOnEveryPath) {
  const Scene scene = test::instanced_scene();
  const Paths paths = make_paths(scene, GetParam());
  std::vector<Ray> rays = random_rays(31, 6000);
  const RaySet primary = primary_rays(scene, 64, 48);
  rays.insert(rays.end(), primary.rays.begin(), primary.rays.end());
  for (size_t i = 0; i < rays.size(); i += 53) rays[i].dir = -rays[i].dir;  // another octant inside a group
  int near_ties = 0;
  for (size_t span : {size_t(9072), size_t(512), size_t(64), size_t(13), size_t(1)})
    EXPECT_GT(expect_same_answers(scene, paths, rays, span, "instances, span " + std::to_string(span), near_ties,
                                  GetParam() == "watertight"),
              3000);
  EXPECT_EQ(near_ties, 0);
}

TEST_P(PacketPaths, HostileSpansThroughInstancesGiveTheSameAnswers) {
  // Large packets and streams go down the instance tree as groups and streams, and regroup in
  // each instance's object space (other octants there, rays whose object-space image needs
  // the exact slab form or is invalid). Spans mixing octants, axis-parallel directions,
  // overflowing inverses and invalid rays, in a scene with world geometry and instances and
  // in one with instances only (no world tree at all).
  Scene only;
  {
    const Scene ball = tessellated_sphere(24, 12), soup = triangle_soup(21, 300);
    const uint32_t b = only.add_instanced_mesh(ball.meshes()[0]), q = only.add_instanced_mesh(soup.meshes()[0]);
    for (int i = 0; i < 12; ++i)
      only.add_instance(
          i % 3 ? b : q,
          test::placement({0.3f, 0.25f + 0.02f * float(i), 0.3f}, {1, float(i % 4), 0.5f}, 30.0f * float(i),
                          {0.5f * float(i % 4) - 0.8f, 0.5f * float(i / 4) - 0.5f, 0.1f * float(i)}));
    const float tiny = 2.0f / kMaxInstanceScale;  // the most shrunk placement allowed
    only.add_instance(b, test::placement({tiny, tiny, tiny}, {0, 1, 0}, 0.0f, {0.05f, 0.0f, 0.0f}));
  }
  const Scene mixed = test::instanced_scene();
  for (const Scene* scene : {&mixed, static_cast<const Scene*>(&only)}) {
    const Paths paths = make_paths(*scene, GetParam());
    std::vector<Ray> rays = random_rays(41, 6000);
    for (size_t i = 0; i < rays.size(); ++i) {
      if (i % 97 == 0) rays[i].org.x = std::numeric_limits<float>::quiet_NaN();
      if (i % 89 == 0) rays[i].dir = Vec3f{0.0f, -1.0f, 0.0f};
      if (i % 79 == 0) rays[i].dir.z = 0x1p-140f;
      if (i % 83 == 0) rays[i].tnear = rays[i].tfar + 1.0f;
      if (i % 7 == 0) rays[i].dir = -rays[i].dir;
    }
    // Camera rays sparse and dense against the instances' leaves: both ways through an
    // instance's mesh (LargePacketTraversal::dense: 8-ray packets or a group).
    for (const auto& [w, h] : {std::pair{64, 48}, std::pair{240, 180}}) {
      const RaySet primary = primary_rays(*scene, w, h);
      rays.insert(rays.end(), primary.rays.begin(), primary.rays.end());
    }
    int near_ties = 0;
    for (size_t span : {size_t(9072), size_t(512), size_t(37)})
      EXPECT_GT(expect_same_answers(*scene, paths, rays, span, "hostile instances, span " + std::to_string(span),
                                    near_ties, GetParam() == "watertight"),
                1000);
    EXPECT_EQ(near_ties, 0);
  }
}

TEST_P(PacketPaths, SharedEdgesOfAnInstanceGiveTheSameAnswersOnEveryPath) {
  // The tessellated sphere placed twice: rotated and scaled, and a second time exactly over
  // the first, so that every hit is an exact tie between two instances of one primitive,
  // which every path gives to the lower instance id.
  const Scene ball = tessellated_sphere(24, 12);
  const Affine3f at = test::placement({0.8f, 0.6f, 0.7f}, {1, 2, 0}, 25.0f, {0.2f, -0.1f, 0.3f});
  Scene scene;
  const uint32_t mesh = scene.add_instanced_mesh(ball.meshes()[0]);
  scene.add_instance(mesh, at);
  scene.add_instance(mesh, at);
  const Paths paths = make_paths(scene, GetParam());
  int near_ties = 0, rays_traced = 0;
  for (const Vec3f& eye : {Vec3f{0.1f, 0.2f, 5.0f}, Vec3f{-3.0f, 2.5f, 2.0f}}) {
    const std::vector<Ray> rays = shared_edge_rays(ball, eye, 7, at);
    for (size_t span : {size_t(256), size_t(9)}) {
      EXPECT_GT(expect_same_answers(scene, paths, rays, span, "instance edges, span " + std::to_string(span),
                                    near_ties, GetParam() == "watertight"),
                500);
      rays_traced += int(rays.size());
    }
    // The tie goes to instance 0. Not asserted for the watertight variant: there the second
    // instance meets the first's hit as tfar, where the bounded filter's documented
    // exception lets Möller–Trumbore decide, whose t may be an ulp nearer than Woop's.
    if (GetParam() == "watertight") continue;
    std::vector<Hit> hits(rays.size());
    paths.single->intersect(rays, hits, Coherence::incoherent);
    for (const Hit& h : hits)
      if (h.hit()) {
        EXPECT_EQ(h.instance_id, 0u);
      }
  }
  EXPECT_LE(near_ties, 3 * rays_traced / 200) << near_ties << " near-ties in " << rays_traced << " rays x 3 paths";
}

INSTANTIATE_TEST_SUITE_P(Simd, PacketPaths, ::testing::Values("default", "median", "watertight", "spatial"),
                         [](const auto& info) { return info.param; });

}  // namespace
}  // namespace rp
