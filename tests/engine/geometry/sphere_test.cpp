// Sphere routines: algebraic, geometric and naive against each other and a long double
// oracle; origins inside, on and outside; cancellation; uv.

#include <gtest/gtest.h>

#include "tests/support/geometry.h"

namespace rp {
namespace {

using namespace rp::test;

TEST(SphereProperty, AlgebraicGeometricAndNaiveAgreeOnRandomRays) {
  std::mt19937 rng(31337);
  int checked = 0, hits = 0;
  for (int i = 0; i < 30000; ++i) {
    const SphereCase<double> s = random_sphere_case<double>(rng, i % 2);
    const SphereReference ref = sphere_reference(s);
    if (ref.tangency < 1e-6L || ref.surface < 1e-6L) continue;
    const Intersection<L> oracle = sphere_oracle(s);
    ++checked;
    hits += oracle.hit;
    const double tol = 1e-9 * double(ref.scale);
    const Intersection<double> alg = intersect_sphere_algebraic(s.ray, s.c, s.radius);
    const Intersection<double> geo = intersect_sphere_geometric(s.ray, s.c, s.radius);
    const Intersection<double> nai = intersect_sphere_naive(s.ray, s.c, s.radius);
    ASSERT_EQ(alg.hit, oracle.hit) << "case " << i;
    ASSERT_EQ(geo.hit, oracle.hit) << "case " << i;
    ASSERT_EQ(nai.hit, oracle.hit) << "case " << i;
    if (!oracle.hit) continue;
    EXPECT_NEAR(alg.t, double(oracle.t), tol) << "case " << i;
    EXPECT_NEAR(geo.t, double(oracle.t), tol) << "case " << i;
    EXPECT_NEAR(nai.t, double(oracle.t), 1e3 * tol) << "case " << i;  // the inaccurate one
    EXPECT_NEAR(alg.t, geo.t, tol) << "case " << i;
    EXPECT_NEAR(alg.v, geo.v, 1e-6) << "case " << i;
  }
  EXPECT_GE(checked, 10000);
  EXPECT_GE(hits, 5000);
}

TEST(SphereProperty, HitsLieOnTheSphereAndUvRoundTrips) {
  std::mt19937 rng(5);
  int hits = 0;
  for (int i = 0; i < 20000; ++i) {
    const SphereCase<double> s = random_sphere_case<double>(rng, i % 3);
    for (const auto& m : sphere_methods<double>()) {
      const Intersection<double> h = m.fn(s.ray, s.c, s.radius);
      if (!h.hit) continue;
      ++hits;
      EXPECT_GE(h.t, s.ray.tnear);
      EXPECT_LE(h.t, s.ray.tfar);
      const Vec3d p = s.ray.at(h.t);
      const double scale = length(s.c) + s.radius + 1;
      const double tol = m.name[0] == 'n' ? 1e-6 : 1e-9;
      EXPECT_NEAR(length(p - s.c), s.radius, tol * scale) << m.name << " case " << i;
      EXPECT_NEAR(length(sphere_normal(s.c, s.radius, p)), 1.0, tol * scale / s.radius);
      ASSERT_GE(h.u, 0.0);
      ASSERT_LT(h.u, 1.0);
      ASSERT_GE(h.v, 0.0);
      ASSERT_LE(h.v, 1.0);
      const double theta = h.v * kPi, phi = h.u * 2 * kPi;
      const Vec3d back = s.c + Vec3d{std::sin(theta) * std::cos(phi), std::cos(theta),
                                     std::sin(theta) * std::sin(phi)} *
                                   s.radius;
      EXPECT_LE(length(back - p), 1e-6 * scale) << m.name << " case " << i;
    }
  }
  EXPECT_GE(hits, 20000);
}

TEST(SphereProperty, OriginInsideOnAndOutsideAllWork) {
  std::mt19937 rng(8);
  for (const auto& m : sphere_methods<double>()) {
    // Outside, sphere ahead: the near root; sphere behind: miss (unless tnear < 0).
    const Vec3d c{1, 2, 3};
    const Intersection<double> ahead = m.fn(make_ray<double>({1, 2, -7}, {0, 0, 2}), c, 5.0);
    ASSERT_TRUE(ahead.hit) << m.name;
    EXPECT_EQ(ahead.t, 2.5) << m.name;
    EXPECT_FALSE(m.fn(make_ray<double>({1, 2, -7}, {0, 0, -2}), c, 5.0).hit) << m.name;
    const Intersection<double> behind =
        m.fn(make_ray<double>({1, 2, -7}, {0, 0, -2}, -kInfT<double>), c, 5.0);
    ASSERT_TRUE(behind.hit) << m.name;
    EXPECT_EQ(behind.t, -7.5) << m.name;
    // Inside: only the far root is ahead.
    const Intersection<double> inside = m.fn(make_ray<double>({1, 2, 4}, {0, 0, -1}), c, 5.0);
    ASSERT_TRUE(inside.hit) << m.name;
    EXPECT_EQ(inside.t, 6.0) << m.name;
    // Exactly on the surface ((3,4,0) etc. from the center, radius 5): t == 0 is a root;
    // with tnear > 0 an inward ray hits the far side at 2 t_p, an outward ray misses.
    for (const Vec3d& f : {Vec3d{3, 4, 0}, Vec3d{0, -5, 0}, Vec3d{-4, 0, 3}, Vec3d{0, 3, -4}}) {
      for (int k = 0; k < 200; ++k) {
        const Vec3d d = uniform_vec(rng, -2.0, 2.0);
        const Rayd r = make_ray(c + f, d);
        const Intersection<double> h = m.fn(r, c, 5.0);
        ASSERT_TRUE(h.hit) << m.name;
        EXPECT_EQ(h.t, 0.0) << m.name;
        RayT<double> later = r;
        later.tnear = 1e-9;
        const Intersection<double> far = m.fn(later, c, 5.0);
        const double tp = -dot(f, d) / dot(d, d);
        if (tp > 1e-6) {
          ASSERT_TRUE(far.hit) << m.name;
          EXPECT_NEAR(far.t, 2 * tp, 1e-12 * (1 + 2 * tp)) << m.name;
        } else if (tp < -1e-6) {
          EXPECT_FALSE(far.hit) << m.name;
        }
      }
    }
    // Within rounding of the surface: t is ~0 or the far root, never anything else.
    for (int k = 0; k < 2000; ++k) {
      const SphereCase<double> s = random_sphere_case<double>(rng, 2);
      RayT<double> r = s.ray;
      r.tnear = 0;
      const Vec3d f = r.org - s.c;
      const double tp = -dot(f, r.dir) / dot(r.dir, r.dir);
      const Intersection<double> h = m.fn(r, s.c, s.radius);
      const double scale = (length(f) + s.radius) / length(r.dir);
      if (h.hit) {
        const bool near_zero = std::abs(h.t) <= 1e-6 * scale;
        const bool far_root = std::abs(h.t - 2 * tp) <= 1e-6 * scale;
        EXPECT_TRUE(near_zero || far_root) << m.name << " t=" << h.t << " tp=" << tp;
      } else {
        EXPECT_LT(tp, 1e-6 * scale) << m.name;  // only an outward ray may miss
      }
    }
  }
}

// An origin inside by a rounding error can compute t_- = tp - t' >= 0 although the true root
// is behind it; the geometric method must then report the far root, as the algebraic one does
// (its c = |f|^2 - r^2 < 0 carries the exact sign).
TEST(SphereProperty, SlightlyInsideOriginDoesNotReportTheRootBehind) {
  // Found by search: here tp - t' rounds to exactly 0.
  const Vec3d c{0.31826446372401485, -3.906639360383581, -3.5396725624340002};
  const double radius = 1.6263662161632497;
  const Vec3d o{1.6491130814989907, -4.8365581418433976, -3.6353808981832545};
  const Vec3d d{-0.73252616150377825, 0.67381342922491028, -0.43490928200914658};
  const Rayd r = make_ray(o, d);
  const Vec3d l = c - r.org;
  ASSERT_LT(dot(l, l), radius * radius);
  const Intersection<double> geo = intersect_sphere_geometric(r, c, radius);
  const Intersection<double> alg = intersect_sphere_algebraic(r, c, radius);
  ASSERT_TRUE(geo.hit && alg.hit);
  EXPECT_GT(geo.t, 1.0);
  EXPECT_NEAR(geo.t, alg.t, 1e-12);
  // And over random origins within rounding of the surface that compute as inside.
  std::mt19937 rng(271);
  int inside = 0;
  for (int i = 0; i < 100000; ++i) {
    const SphereCase<double> s = random_sphere_case<double>(rng, 2);
    RayT<double> ray = s.ray;
    ray.tnear = 0;
    const Vec3d f = ray.org - s.c;
    if (!(dot(f, f) < s.radius * s.radius)) continue;
    ++inside;
    const double tp = -dot(f, ray.dir) / dot(ray.dir, ray.dir);
    const Intersection<double> h = intersect_sphere_geometric(ray, s.c, s.radius);
    ASSERT_TRUE(h.hit) << "case " << i;
    EXPECT_GT(h.t, tp) << "case " << i;
  }
  EXPECT_GE(inside, 10000);
}

// Haines et al.'s discriminant avoids the cancellation of b^2 - 4ac for a distant sphere:
// float rays from distance 1000 at a unit sphere, aimed within 0.999 radii of the center.
TEST(SphereProperty, AlgebraicStaysAccurateWhereNaiveCancelsFloat) {
  std::mt19937 rng(5);
  double alg_err = 0, naive_err = 0;
  int naive_misses = 0, cases = 0;
  for (int i = 0; i < 20000; ++i) {
    const Vec3f o = Vec3f(unit_vec<double>(rng) * 1000.0);
    const Vec3d aim = unit_vec<double>(rng) * uniform(rng, 0.0, 0.999);
    const Vec3f d = Vec3f(normalize(aim - Vec3d(o)));
    const Ray r = make_ray(o, d);
    const Intersection<L> ref = intersect_sphere_algebraic(
        RayT<L>{Vec3<L>(o), 0, Vec3<L>(d), kInfT<L>}, Vec3<L>(0.0L), 1.0L);
    if (!ref.hit) continue;
    ++cases;
    const Intersection<float> alg = intersect_sphere_algebraic(r, Vec3f(0.0f), 1.0f);
    const Intersection<float> nai = intersect_sphere_naive(r, Vec3f(0.0f), 1.0f);
    ASSERT_TRUE(alg.hit) << "case " << i;
    alg_err = std::max(alg_err, double(std::abs(alg.t - ref.t)));
    if (nai.hit) {
      naive_err = std::max(naive_err, double(std::abs(nai.t - ref.t)));
    } else {
      ++naive_misses;
    }
  }
  EXPECT_GE(cases, 10000);
  EXPECT_LE(alg_err, 1e-3);  // about 3 float ulps of t ~ 1000
  EXPECT_GT(naive_err, 10 * alg_err);
  RecordProperty("algebraic_max_abs_error", std::to_string(alg_err));
  RecordProperty("naive_max_abs_error", std::to_string(naive_err));
  RecordProperty("naive_false_misses", naive_misses);
}

TEST(SphereProperty, DirectionLengthScalesT) {
  const Vec3d c{0, 0, 10};
  for (const auto& m : sphere_methods<double>()) {
    for (double k : {0.125, 1.0, 4.0, 1024.0}) {
      const Intersection<double> h = m.fn(make_ray<double>({0, 0, 0}, {0, 0, k}), c, 2.0);
      ASSERT_TRUE(h.hit) << m.name;
      EXPECT_DOUBLE_EQ(h.t, 8.0 / k) << m.name;
    }
    EXPECT_FALSE(m.fn(make_ray<double>({0, 0, 0}, {0, 0, 0}), c, 2.0).hit) << m.name;
  }
}

TEST(SphereProperty, FloatMethodsAgreeAwayFromTangency) {
  std::mt19937 rng(17);
  int checked = 0;
  for (int i = 0; i < 20000; ++i) {
    const SphereCase<float> s = random_sphere_case<float>(rng, i % 2);
    const SphereReference ref = sphere_reference(s);
    if (ref.tangency < 1e-2L || ref.surface < 1e-2L) continue;
    const Intersection<L> oracle = sphere_oracle(s);
    ++checked;
    for (const auto& m : sphere_methods<float>()) {
      const Intersection<float> h = m.fn(s.ray, s.c, s.radius);
      ASSERT_EQ(h.hit, oracle.hit) << m.name << " case " << i;
      if (h.hit) {
        EXPECT_NEAR(h.t, double(oracle.t), 1e-4 * double(ref.scale)) << m.name;
      }
    }
  }
  EXPECT_GE(checked, 10000);
}

TEST(SphereUv, PolesAndEquatorHaveTheDocumentedValues) {
  const Vec3d c{1, 1, 1};
  struct Expect {
    Vec3d dir_from_center;
    double u, v;
  };
  for (const Expect& e : {Expect{{0, 1, 0}, 0, 0}, Expect{{0, -1, 0}, 0, 1},
                          Expect{{1, 0, 0}, 0, 0.5}, Expect{{0, 0, 1}, 0.25, 0.5},
                          Expect{{-1, 0, 0}, 0.5, 0.5}, Expect{{0, 0, -1}, 0.75, 0.5}}) {
    // A ray from outside straight at the center hits the point center + 2 * dir.
    const Vec3d o = c + e.dir_from_center * 5.0;
    for (const auto& m : sphere_methods<double>()) {
      const Intersection<double> h = m.fn(make_ray(o, c - o), c, 2.0);
      ASSERT_TRUE(h.hit) << m.name;
      EXPECT_NEAR(h.t, 0.6, 1e-15) << m.name;
      EXPECT_NEAR(h.u, e.u, 1e-15) << m.name;
      EXPECT_NEAR(h.v, e.v, 1e-15) << m.name;
    }
    const Vec2<double> uv = sphere_uv(c, 2.0, c + e.dir_from_center * 2.0);
    EXPECT_NEAR(uv.x, e.u, 1e-15);
    EXPECT_NEAR(uv.y, e.v, 1e-15);
  }
  EXPECT_EQ(sphere_normal(c, 2.0, Vec3d{1, 3, 1}), (Vec3d{0, 1, 0}));
  // u stays below 1 just under phi = 2 pi (z slightly negative, x positive).
  const Vec2<float> uv = sphere_uv(Vec3f{0, 0, 0}, 1.0f, Vec3f{1, 0, -1e-9f});
  EXPECT_GE(uv.x, 0.0f);
  EXPECT_LT(uv.x, 1.0f);
}

}  // namespace
}  // namespace rp
