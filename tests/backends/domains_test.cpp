// The data-parallel simulation (analysis/domains.h): disjoint cells covering the scene
// with the triangles that reach into each, rays forwarded along the cells with the counts
// worked out by hand, and the domains' answers those of one backend over the whole scene.

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <memory>
#include <vector>

#include "analysis/domains.h"
#include "analysis/raygen.h"
#include "backends/registry.h"
#include "base/error.h"
#include "tests/support/scenes.h"

namespace rp {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

std::vector<std::unique_ptr<Backend>> backends_of(const Domains& d) {
  std::vector<std::unique_ptr<Backend>> out;
  for (const Scene& part : d.parts) out.push_back(make_backend("embree", part));
  return out;
}

TEST(Domains, CellsCoverTheSceneWithoutOverlapAndHoldTheTrianglesReachingIntoThem) {
  const Scene scene = test::triangle_soup(3, 1001);
  const MeshView& mesh = scene.meshes()[0];
  for (int count : {1, 2, 3, 7, 16}) {
    const Domains d = split_domains(scene, count);
    ASSERT_EQ(d.cells.size(), size_t(count));
    ASSERT_EQ(d.parts.size(), size_t(count));
    Box3f all;
    uint64_t held = 0;
    for (size_t k = 0; k < d.cells.size(); ++k) {
      all.extend(d.cells[k]);
      // No two cells share volume.
      for (size_t j = 0; j < k; ++j) {
        float volume = 1;
        for (int a = 0; a < 3; ++a)
          volume *= std::max(0.0f, std::min(d.cells[k].hi[a], d.cells[j].hi[a]) - std::max(d.cells[k].lo[a], d.cells[j].lo[a]));
        EXPECT_EQ(volume, 0.0f) << count << " domains, cells " << j << " and " << k;
      }
      // Exactly the triangles whose bounds reach into the cell.
      uint32_t reaching = 0;
      for (uint32_t t = 0; t < mesh.triangle_count(); ++t) {
        Box3f b;
        for (int c = 0; c < 3; ++c) b.extend(mesh.vertex(t, c));
        bool in = true;
        for (int a = 0; a < 3; ++a) in = in && b.lo[a] <= d.cells[k].hi[a] && d.cells[k].lo[a] <= b.hi[a];
        reaching += in;
      }
      EXPECT_EQ(d.parts[k].triangle_count(), reaching) << count << " domains, cell " << k;
      held += d.parts[k].triangle_count();
    }
    EXPECT_EQ(all, scene.bounds()) << count;
    EXPECT_EQ(d.triangles, held);
    EXPECT_GE(held, scene.triangle_count());
  }
  EXPECT_THROW(split_domains(scene, 1002), Error);
  EXPECT_THROW(split_domains(make_default_scene(), 2), Error);  // analytic primitives
}

TEST(Domains, RaysVisitTheCellsAlongThemUntilOneFindsAHit) {
  // Cell 0, x in [-1, 5]: a triangle at x = 0 over the half y + z <= 0 of the square y, z in
  // [-1, 1]; cell 1, x in [5, 15]: the whole square at x = 10.
  TriangleMesh half, square;
  half.positions = {{0, -1, -1}, {0, 1, -1}, {0, -1, 1}};
  half.indices = {0, 1, 2};
  square.positions = {{10, -1, -1}, {10, 1, -1}, {10, 1, 1}, {10, -1, 1}};
  square.indices = {0, 1, 2, 0, 2, 3};
  Domains d;
  d.cells = {Box3f({-1, -1, -1}, {5, 1, 1}), Box3f({5, -1, -1}, {15, 1, 1})};
  d.parts.resize(2);
  d.parts[0].add_mesh(half);
  d.parts[1].add_mesh(square);
  Scene scene;
  scene.add_mesh(half);
  scene.add_mesh(square);
  const auto backends = backends_of(d);
  const auto whole = make_backend("embree", scene);
  const Vec3f x{1, 0, 0};
  const std::vector<Ray> rays = {
      {{-5, -0.5f, -0.5f}, 0, x, kInf},  // cell 0 finds the triangle at t = 5
      {{-5, 0.5f, 0.5f}, 0, x, kInf},    // cell 0 finds nothing: forwarded, cell 1 finds the square at 15
      {{-5, 2, 0}, 0, x, kInf},          // passes both cells by
      {{7, 0.5f, 0.5f}, 0, x, kInf},     // starts in cell 1, past cell 0
      {{-5, 0.5f, 0.5f}, 0, x, 12},      // forwarded, but the square lies beyond its tfar
      {{20, 0, 0}, 0, -x, kInf}};        // cell 1 first, which finds the square: cell 0 is never asked
  for (const bool any : {false, true}) {
    const Traffic t = follow_rays(d, backends, *whole, rays, any);
    EXPECT_EQ(t.rays, 6u);
    EXPECT_EQ(t.visits, 1u + 2u + 0u + 1u + 2u + 1u) << any;
    EXPECT_EQ(t.forwards, 2u) << any;
    EXPECT_EQ(t.one_domain, 3u) << any;
    EXPECT_EQ(t.no_domain, 1u) << any;
    EXPECT_EQ(t.max_visits, 2u) << any;
    EXPECT_EQ(t.hits, 4u) << any;
    EXPECT_EQ(t.disagreements, 0u) << any;
  }
}

TEST(Domains, ForwardedRaysFindTheWholeScenesHits) {
  const Scene scene = test::triangle_soup(9, 4000);
  const auto whole = make_backend("embree", scene);
  const RaySet rays = random_rays(scene, 4000, 2);
  uint64_t forwards = 0;
  for (int count : {2, 5, 8}) {
    const Domains d = split_domains(scene, count);
    const auto backends = backends_of(d);
    for (bool any : {false, true}) {
      const Traffic t = follow_rays(d, backends, *whole, rays.rays, any);
      EXPECT_EQ(t.disagreements, 0u) << count << (any ? " any hit" : " closest");
      EXPECT_GT(t.hits, 1000u);
      EXPECT_EQ(t.visits, t.forwards + t.rays - t.no_domain);  // a ray that enters a domain visits it
      forwards += t.forwards;
    }
  }
  EXPECT_GT(forwards, 0u) << "the soup's random rays cross domains";
}

}  // namespace
}  // namespace rp
