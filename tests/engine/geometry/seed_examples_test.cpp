// The lecture notes' worked examples with their exact answers: the ellipsoid, the box slabs,
// the plane and the Möller–Trumbore derivation.

#include <gtest/gtest.h>

#include "tests/support/geometry.h"

namespace rp {
namespace {

using namespace rp::test;

// Lecture notes "Ray-Surface Intersection", section 1 question 4: (x-2)^2/4 + (y-2)^2 + z^2/4 = 1, r(t) = t (1, 1, 0).
template <typename T>
void check_seed_ellipsoid(T rel) {
  const T root = std::sqrt(T(4) / T(5));
  const T t_first = T(2) - root;
  const T t_second = T(2) + root;
  Quadric<T> direct;  // the seed's equation expanded by hand: x^2/4 + y^2 + z^2/4 - x - 4y + 4
  direct.A = T(0.25);
  direct.B = T(1);
  direct.C = T(0.25);
  direct.G = T(-1);
  direct.H = T(-4);
  direct.J = T(4);
  const Quadric<T> named = Quadric<T>::ellipsoid({T(2), T(2), T(0)}, {T(2), T(1), T(2)});
  // The named constructor writes the same function around its centre (2, 2, 0).
  for (const Vec3<T>& p : {Vec3<T>{0, 0, 0}, Vec3<T>{2, 2, 0}, Vec3<T>{4, 2, 0}, Vec3<T>{1, 3, -1}, Vec3<T>{-3, 5, 7}}) {
    EXPECT_NEAR(named.eval(p), direct.eval(p), T(1e-5) * (T(1) + std::abs(direct.eval(p))));
    EXPECT_NEAR(length(named.gradient(p) - direct.gradient(p)), T(0), T(1e-5) * (T(1) + length(direct.gradient(p))));
  }
  const RayT<T> r = make_ray<T>({0, 0, 0}, {1, 1, 0});
  for (const Quadric<T>& q : {direct, named}) {
    const Intersection<T> h = intersect_quadric(r, q);
    ASSERT_TRUE(h.hit);
    EXPECT_TRUE(close_rel(h.t, t_first, rel)) << h.t << " vs " << t_first;
    const Vec3<T> p = r.at(h.t);
    EXPECT_TRUE(close_rel(p.x, T(2) - root, rel));
    EXPECT_TRUE(close_rel(p.y, T(2) - root, rel));
    EXPECT_EQ(p.z, T(0));
    EXPECT_EQ(h.u, T(0));
    EXPECT_EQ(h.v, T(0));
    // The second root, once the first is excluded by tnear.
    RayT<T> r2 = r;
    r2.tnear = T(2);
    const Intersection<T> h2 = intersect_quadric(r2, q);
    ASSERT_TRUE(h2.hit);
    EXPECT_TRUE(close_rel(h2.t, t_second, rel)) << h2.t << " vs " << t_second;
  }
}

TEST(SeedExamples, EllipsoidHitsAtTwoMinusSqrtFourFifthsDouble) {
  check_seed_ellipsoid<double>(1e-12);
}

TEST(SeedExamples, EllipsoidHitsAtTwoMinusSqrtFourFifthsFloat) {
  check_seed_ellipsoid<float>(1e-5f);
}

// Lecture notes "Ray-Surface Intersection", section 3 questions 2-5: box (-2,-2,-2)-(2,2,2), ray (-3,4,5) + t(1,-1,-2).
template <typename T>
void check_seed_box() {
  const RayT<T> r = make_ray<T>({-3, 4, 5}, {1, -1, -2});
  const SlabInterval<T> sx = slab_interval<T>(-3, 1, -2, 2);
  const SlabInterval<T> sy = slab_interval<T>(4, -1, -2, 2);
  const SlabInterval<T> sz = slab_interval<T>(5, -2, -2, 2);
  EXPECT_EQ(sx.t_min, T(1));
  EXPECT_EQ(sx.t_max, T(5));
  EXPECT_EQ(sy.t_min, T(2));
  EXPECT_EQ(sy.t_max, T(6));
  EXPECT_EQ(sz.t_min, T(1.5));
  EXPECT_EQ(sz.t_max, T(3.5));

  // The same per-axis slabs through intersect_box, with boxes unbounded in the other axes.
  const T inf = kInfT<T>;
  const SlabHit<T> only_x = intersect_box(r, Box3<T>({-2, -inf, -inf}, {2, inf, inf}));
  const SlabHit<T> only_y = intersect_box(r, Box3<T>({-inf, -2, -inf}, {inf, 2, inf}));
  const SlabHit<T> only_z = intersect_box(r, Box3<T>({-inf, -inf, -2}, {inf, inf, 2}));
  ASSERT_TRUE(only_x.hit && only_y.hit && only_z.hit);
  EXPECT_EQ(only_x.t_enter, T(1));
  EXPECT_EQ(only_x.t_exit, T(5));
  EXPECT_EQ(only_y.t_enter, T(2));
  EXPECT_EQ(only_y.t_exit, T(6));
  EXPECT_EQ(only_z.t_enter, T(1.5));
  EXPECT_EQ(only_z.t_exit, T(3.5));

  const SlabHit<T> h = intersect_box(r, Box3<T>({-2, -2, -2}, {2, 2, 2}));
  ASSERT_TRUE(h.hit);
  EXPECT_EQ(h.t_enter, T(2));
  EXPECT_EQ(h.t_exit, T(3.5));
  EXPECT_EQ(r.at(h.t_enter), (Vec3<T>{-1, 2, 1}));
  EXPECT_EQ(r.at(h.t_exit), (Vec3<T>{0.5, 0.5, -2}));
}

TEST(SeedExamples, BoxSlabsEntryAndExitMatchWorkedExample) {
  check_seed_box<double>();
  check_seed_box<float>();
}

// Lecture notes "Ray-Surface Intersection", section 1 question 1-3: plane (p - p') . N = 0; t < 0 means no hit.
TEST(SeedExamples, PlaneHitBehindOriginIsNotAHit) {
  const Vec3d n{0, 0, 1};
  const double d = -2;  // z = 2
  EXPECT_FALSE(intersect_plane(make_ray<double>({0, 0, 5}, {0, 0, 1}), n, d).hit);
  const Intersection<double> front = intersect_plane(make_ray<double>({0, 0, 5}, {0, 0, -1}), n, d);
  ASSERT_TRUE(front.hit);
  EXPECT_EQ(front.t, 3.0);
  // Both faces are hit: from below (n . dir > 0) as well.
  const Intersection<double> back = intersect_plane(make_ray<double>({1, 2, 0}, {0, 0, 0.5}), n, d);
  ASSERT_TRUE(back.hit);
  EXPECT_EQ(back.t, 4.0);
  // A negative tnear admits the root behind the origin.
  const Intersection<double> behind =
      intersect_plane(make_ray<double>({0, 0, 5}, {0, 0, 1}, -10.0), n, d);
  ASSERT_TRUE(behind.hit);
  EXPECT_EQ(behind.t, -3.0);
}

// Lecture notes "Ray-Surface Intersection", section 1: d . N = 0 is no hit, whether the line lies in the plane or not.
TEST(SeedExamples, PlaneParallelRayMissesInPlaneAndOffPlane) {
  const Vec3d n{0, 0, 2};
  const double d = -4;  // z = 2
  for (double tnear : {0.0, -kInfT<double>}) {
    EXPECT_FALSE(intersect_plane(make_ray<double>({0, 0, 2}, {1, 1, 0}, tnear), n, d).hit);
    EXPECT_FALSE(intersect_plane(make_ray<double>({0, 0, 3}, {1, -1, 0}, tnear), n, d).hit);
    EXPECT_FALSE(intersect_plane(make_ray<double>({0, 0, 3}, {-0.0, 1, 0.0}, tnear), n, d).hit);
  }
  const Vec3f nf{0, 0, 2};
  EXPECT_FALSE(intersect_plane(make_ray<float>({0, 0, 2}, {1, 1, 0}), nf, -4.0f).hit);
  EXPECT_FALSE(intersect_plane(make_ray<float>({0, 0, 3}, {1, 1, 0}), nf, -4.0f).hit);
}

// Lecture notes "Ray-Surface Intersection", section 2 questions 1-2:
// Cramer's rule on [-D, E1, E2][t, b1, b2]^T = O - P0
// reduces to Möller-Trumbore via the determinant identities (13)-(16).
TEST(SeedExamples, MollerTrumboreEqualsCramerOnTheDerivation) {
  std::mt19937 rng(2);
  for (int i = 0; i < 1000; ++i) {
    const Vec3d d = uniform_vec(rng, -2.0, 2.0);
    const Vec3d e1 = uniform_vec(rng, -2.0, 2.0);
    const Vec3d e2 = uniform_vec(rng, -2.0, 2.0);
    const Vec3d s = uniform_vec(rng, -2.0, 2.0);
    const Vec3d s1 = cross(d, e2);
    const Vec3d s2 = cross(s, e1);
    EXPECT_NEAR(det3_columns(-d, e1, e2), dot(s1, e1), 1e-12);  // (13)
    EXPECT_NEAR(det3_columns(s, e1, e2), dot(s2, e2), 1e-12);   // (14)
    EXPECT_NEAR(det3_columns(-d, s, e2), dot(s1, s), 1e-12);    // (15)
    EXPECT_NEAR(det3_columns(-d, e1, s), dot(s2, d), 1e-12);    // (16)
  }
  // Triangle (1,0,0), (0,1,0), (0,0,1) and the ray from the origin along (1,1,1):
  // t = b1 = b2 = 1/3 by both.
  const Vec3d v0{1, 0, 0}, v1{0, 1, 0}, v2{0, 0, 1};
  const Rayd r = make_ray<double>({0, 0, 0}, {1, 1, 1});
  const Intersection<double> mt = intersect_triangle_mt(r, v0, v1, v2);
  const Intersection<double> cr = intersect_triangle_cramer(r, v0, v1, v2);
  ASSERT_TRUE(mt.hit && cr.hit);
  for (double x : {mt.t, mt.u, mt.v, cr.t, cr.u, cr.v}) EXPECT_NEAR(x, 1.0 / 3.0, 1e-15);
  // And on random rays they agree to rounding.
  for (int i = 0; i < 2000; ++i) {
    const Vec3d a = uniform_vec(rng, -1.0, 1.0), b = uniform_vec(rng, -1.0, 1.0),
                c = uniform_vec(rng, -1.0, 1.0);
    const Vec3d o = uniform_vec(rng, -3.0, 3.0);
    const Vec3d target = a + (b - a) * 0.3 + (c - a) * 0.3;
    const Rayd ray = make_ray(o, target - o);
    const Intersection<double> x = intersect_triangle_mt(ray, a, b, c);
    const Intersection<double> y = intersect_triangle_cramer(ray, a, b, c);
    ASSERT_TRUE(x.hit && y.hit) << i;
    EXPECT_TRUE(close_rel(x.t, y.t, 1e-9));
    EXPECT_TRUE(close_rel(x.u, y.u, 1e-9));
    EXPECT_TRUE(close_rel(x.v, y.v, 1e-9));
  }
}

}  // namespace
}  // namespace rp
