// The data-parallel simulation (engine/analysis/domains.h): domains of equal size that hold
// every triangle once, rays forwarded in entry order with the counts worked out by hand, and
// the domains' answers those of one backend over the whole scene.

#include <gtest/gtest.h>

#include <limits>
#include <memory>
#include <vector>

#include "backends/registry.h"
#include "engine/analysis/domains.h"
#include "engine/analysis/raygen.h"
#include "engine/error.h"
#include "tests/support/scenes.h"

namespace rp {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

std::vector<std::unique_ptr<Backend>> backends_of(const Domains& d) {
  std::vector<std::unique_ptr<Backend>> out;
  for (const Scene& part : d.parts) out.push_back(make_backend("embree", part));
  return out;
}

TEST(Domains, SplitHoldsEveryTriangleOnceInPartsOfEqualSize) {
  const Scene scene = test::triangle_soup(3, 1001);
  for (int count : {1, 2, 3, 7, 16}) {
    const Domains d = split_domains(scene, count);
    ASSERT_EQ(d.parts.size(), size_t(count));
    uint32_t total = 0, lo = ~0u, hi = 0;
    for (size_t k = 0; k < d.parts.size(); ++k) {
      const uint32_t n = d.parts[k].triangle_count();
      total += n;
      lo = std::min(lo, n);
      hi = std::max(hi, n);
      EXPECT_EQ(d.bounds[k], d.parts[k].bounds()) << count << " domains, part " << k;
    }
    EXPECT_EQ(total, scene.triangle_count()) << count;
    EXPECT_LE(hi - lo, 1u) << count;
  }
  EXPECT_THROW(split_domains(scene, 1002), Error);
  EXPECT_THROW(split_domains(make_default_scene(), 2), Error);  // analytic primitives
}

TEST(Domains, RaysVisitTheDomainsTheyEnterNearestFirstUntilAHitIsNearerThanTheNext) {
  // Domain 0: one triangle at x = 0 over half of the square y, z in [-1, 1] (y + z <= 0 is
  // covered), so its bounds are the whole square; domain 1: a square at x = 10.
  Scene scene;
  TriangleMesh m;
  m.positions = {{0, -1, -1}, {0, 1, -1}, {0, -1, 1}, {10, -1, -1}, {10, 1, -1}, {10, 1, 1}, {10, -1, 1}};
  m.indices = {0, 1, 2, 3, 4, 5, 3, 5, 6};
  scene.add_mesh(m);
  const Domains d = split_domains(scene, 2);
  ASSERT_EQ(d.parts[0].triangle_count(), 1u);
  const auto backends = backends_of(d);
  const auto whole = make_backend("embree", scene);
  const Vec3f x{1, 0, 0};
  const std::vector<Ray> rays = {
      {{-5, -0.5f, -0.5f}, 0, x, kInf},  // hits domain 0 at t = 5: stops there (domain 1 starts at 15)
      {{-5, 0.5f, 0.5f}, 0, x, kInf},    // through domain 0's bounds, misses its triangle: forwarded, hits at 15
      {{-5, 2, 0}, 0, x, kInf},          // enters neither
      {{5, 0.5f, 0.5f}, 0, x, kInf},     // starts past domain 0: domain 1 only
      {{-5, 0.5f, 0.5f}, 0, x, 12},      // forwarded? no: domain 1 lies beyond its tfar
      {{15, 0, 0}, 0, -x, kInf}};        // domain 1 first (t = 5), then domain 0 at 15 is beyond its hit
  const Traffic t = follow_rays(d, backends, *whole, rays, false);
  EXPECT_EQ(t.rays, 6u);
  EXPECT_EQ(t.visits, 1u + 2u + 0u + 1u + 1u + 1u);
  EXPECT_EQ(t.forwards, 1u);
  EXPECT_EQ(t.one_domain, 4u);
  EXPECT_EQ(t.no_domain, 1u);
  EXPECT_EQ(t.max_visits, 2u);
  EXPECT_EQ(t.hits, 4u);
  EXPECT_EQ(t.disagreements, 0u);
  // Any hit stops at the first domain that blocks: the second ray still visits both.
  const Traffic s = follow_rays(d, backends, *whole, rays, true);
  EXPECT_EQ(s.visits, 1u + 2u + 0u + 1u + 1u + 1u);
  EXPECT_EQ(s.hits, 4u);
  EXPECT_EQ(s.disagreements, 0u);
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
