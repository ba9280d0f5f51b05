// Quadrics: the named constructors against closed-form hits, clipping, the linear case, the
// long double oracle and exact scaling.

#include <gtest/gtest.h>

#include "tests/support/geometry.h"

namespace rp {
namespace {

using namespace rp::test;

enum class Shape { ellipsoid, cylinder, cone, hyperboloid1, hyperboloid2, paraboloid };
constexpr std::array<Shape, 6> kShapes = {Shape::ellipsoid,    Shape::cylinder,
                                          Shape::cone,         Shape::hyperboloid1,
                                          Shape::hyperboloid2, Shape::paraboloid};

/// Unit vector along axis m.
Vec3d axis_vec(int m) {
  Vec3d e(0.0);
  e[m] = 1;
  return e;
}

/// The radial axes (i < j) for symmetry axis k, as documented on Quadric.
std::array<int, 2> radial_axes(int k) { return {k == 0 ? 1 : 0, k == 2 ? 1 : 2}; }

struct ShapeParams {
  Vec3d center;
  double a, b, c, h;  // radial a/b, axial c (hyperboloids), half height or height
};

Quadric<double> make_shape(Shape s, const ShapeParams& p, int axis) {
  switch (s) {
    case Shape::ellipsoid: {
      Vec3d radii(0.0);
      const auto r = radial_axes(axis);
      radii[r[0]] = p.a;
      radii[r[1]] = p.b;
      radii[axis] = p.c;
      return Quadric<double>::ellipsoid(p.center, radii);
    }
    case Shape::cylinder: return Quadric<double>::cylinder(p.center, p.a, p.b, p.h, axis);
    case Shape::cone: return Quadric<double>::cone(p.center, p.a, p.b, p.h, axis);
    case Shape::hyperboloid1:
      return Quadric<double>::hyperboloid_one_sheet(p.center, p.a, p.b, p.c, p.h, axis);
    case Shape::hyperboloid2:
      return Quadric<double>::hyperboloid_two_sheets(p.center, p.a, p.b, p.c, p.h, axis);
    case Shape::paraboloid: return Quadric<double>::paraboloid(p.center, p.a, p.b, p.h, axis);
  }
  return {};
}

/// A point on the clipped surface from its parameters: angle phi around the axis and
/// s in [0, 1] along it.
Vec3d shape_point(Shape s, const ShapeParams& p, int axis, double phi, double s01) {
  const auto r = radial_axes(axis);
  double radial = 1, axial = 0;
  switch (s) {
    case Shape::ellipsoid: {
      const double theta = s01 * kPi;
      radial = std::sin(theta);
      axial = p.c * std::cos(theta);
      break;
    }
    case Shape::cylinder: axial = (2 * s01 - 1) * p.h; break;
    case Shape::cone:
      axial = (2 * s01 - 1) * p.h;
      radial = std::abs(axial);
      break;
    case Shape::hyperboloid1:
      axial = (2 * s01 - 1) * p.h;
      radial = std::sqrt(1 + (axial / p.c) * (axial / p.c));
      break;
    case Shape::hyperboloid2: {
      // Upper or lower sheet, |axial| in [c, h].
      const double mag = p.c + (p.h - p.c) * std::abs(2 * s01 - 1);
      axial = s01 < 0.5 ? -mag : mag;
      radial = std::sqrt(std::max(0.0, (axial / p.c) * (axial / p.c) - 1));
      break;
    }
    case Shape::paraboloid:
      axial = s01 * p.h;
      radial = std::sqrt(axial / p.h);
      break;
  }
  Vec3d q = p.center;
  q[r[0]] += p.a * radial * std::cos(phi);
  q[r[1]] += p.b * radial * std::sin(phi);
  q[axis] += axial;
  return q;
}

TEST(QuadricConstructors, SurfacePointsEvaluateToZeroAndLieInClip) {
  std::mt19937 rng(3);
  const ShapeParams p{{0.5, -1.25, 2}, 1.5, 0.75, 1.25, 3};
  for (Shape s : kShapes) {
    for (int axis = 0; axis < 3; ++axis) {
      const Quadric<double> q = make_shape(s, p, axis);
      for (int k = 0; k < 500; ++k) {
        const Vec3d x =
            shape_point(s, p, axis, uniform(rng, 0.0, 2 * kPi), uniform(rng, 0.0, 1.0));
        const double g = length(q.gradient(x));
        EXPECT_LE(std::abs(q.eval(x)), 1e-12 * (g + 1)) << int(s) << " axis " << axis;
        EXPECT_TRUE(q.clip.contains(x)) << int(s) << " axis " << axis;
        EXPECT_EQ(q.bounds(), q.clip);
      }
    }
  }
}

TEST(QuadricConstructors, RaysHitAtClosedFormT) {
  const Vec3d c{0.5, -1.25, 2};
  for (int k = 0; k < 3; ++k) {
    const auto r = radial_axes(k);
    const Vec3d ei = axis_vec(r[0]), ej = axis_vec(r[1]), ek = axis_vec(k);
    struct Case {
      const char* name;
      Quadric<double> q;
      Vec3d org, dir;
      double t;
    };
    const Case cases[] = {
        // Cylinder radius 2 from outside: t = distance - 2, along either radial axis.
        {"cylinder_i", Quadric<double>::cylinder(c, 2, 2, 5, k), c + ei * 10.0 + ek, -ei, 8},
        {"cylinder_j", Quadric<double>::cylinder(c, 2, 2, 5, k), c - ej * 7.0, ej, 5},
        {"elliptic_cylinder", Quadric<double>::cylinder(c, 1, 3, 5, k), c + ej * 10.0, -ej, 7},
        // Cone slope 0.5: radius 1 at height 2; and down the axis onto the apex.
        {"cone_side", Quadric<double>::cone(c, 0.5, 0.5, 4, k), c + ek * 2.0 + ei * 10.0, -ei, 9},
        {"cone_apex", Quadric<double>::cone(c, 0.5, 0.5, 4, k), c + ek * 10.0, -ek, 10},
        // Hyperboloid of one sheet a = b = c = 1: radius sqrt(2) at height 1.
        {"hyperboloid1", Quadric<double>::hyperboloid_one_sheet(c, 1, 1, 1, 3, k),
         c + ek + ei * 10.0, -ei, 10 - std::sqrt(2.0)},
        // Hyperboloid of two sheets c = 2: vertex at axial 2.
        {"hyperboloid2", Quadric<double>::hyperboloid_two_sheets(c, 1, 1, 2, 5, k),
         c + ek * 10.0, -ek, 8},
        {"hyperboloid2_lower", Quadric<double>::hyperboloid_two_sheets(c, 1, 1, 2, 5, k),
         c - ek * 10.0, ek, 8},
        // Paraboloid rim radius 2 at height 4: radius 1 at height 1; vertex down the axis.
        {"paraboloid_side", Quadric<double>::paraboloid(c, 2, 2, 4, k), c + ek + ei * 10.0, -ei,
         9},
        {"paraboloid_vertex", Quadric<double>::paraboloid(c, 2, 2, 4, k), c + ek * 10.0, -ek, 10},
    };
    for (const Case& cs : cases) {
      const Intersection<double> h = intersect_quadric(make_ray(cs.org, cs.dir), cs.q);
      ASSERT_TRUE(h.hit) << cs.name << " axis " << k;
      EXPECT_NEAR(h.t, cs.t, 1e-12 * cs.t) << cs.name << " axis " << k;
    }
    // Ellipsoid radii per world axis (no axis parameter): t = 10 - radius.
    const Quadric<double> e = Quadric<double>::ellipsoid(c, {1, 2, 3});
    const Intersection<double> he = intersect_quadric(make_ray(c + ek * 10.0, -ek), e);
    ASSERT_TRUE(he.hit);
    EXPECT_NEAR(he.t, 10.0 - (k + 1), 1e-12);
  }
  // Float: the cylinder from outside.
  const Quadric<float> cyl = Quadric<float>::cylinder({0, 0, 0}, 2, 2, 1);
  const Intersection<float> hf = intersect_quadric(make_ray<float>({10, 0.5f, 0}, {-1, 0, 0}), cyl);
  ASSERT_TRUE(hf.hit);
  EXPECT_FLOAT_EQ(hf.t, 8.0f);
}

TEST(QuadricProperty, ClippedFirstRootFallsBackToSecond) {
  // Cylinder radius 1 along y clipped to |y| <= 1; the ray enters the infinite cylinder above
  // the clip (first root clipped) and leaves it inside the clip (second root accepted).
  const Quadric<double> q = Quadric<double>::cylinder({0, 0, 0}, 1, 1, 1);
  const Rayd r = make_ray<double>({-1, 3, 0}, {1, -1.5, 0});
  const Intersection<double> h = intersect_quadric(r, q);
  ASSERT_TRUE(h.hit);
  EXPECT_NEAR(h.t, 2.0, 1e-15);
  EXPECT_NEAR(r.at(h.t).x, 1.0, 1e-15);
  // Both roots clipped: miss.
  EXPECT_FALSE(intersect_quadric(make_ray<double>({-3, 5, 0}, {1, 0, 0}), q).hit);
  // Unclipped (default clip is all of space): the first root.
  Quadric<double> open = q;
  open.clip = Quadric<double>{}.clip;
  const Intersection<double> ho = intersect_quadric(r, open);
  ASSERT_TRUE(ho.hit);
  EXPECT_NEAR(ho.t, 0.0, 1e-15);
}

TEST(QuadricProperty, LinearCaseHasOneRootAndDegenerateLineMisses) {
  // Paraboloid y = x^2 + z^2 (rim radius 1 at height 1), ray parallel to the axis: a == 0.
  const Quadric<double> par = Quadric<double>::paraboloid({0, 0, 0}, 1, 1, 1);
  const Intersection<double> hp = intersect_quadric(make_ray<double>({0.5, 5, 0}, {0, -1, 0}), par);
  ASSERT_TRUE(hp.hit);
  EXPECT_EQ(hp.t, 4.75);
  // Cone x^2 + z^2 = y^2, ray parallel to a generator: a == 0, one root at t = 0.5.
  const Quadric<double> cone = Quadric<double>::cone({0, 0, 0}, 1, 1, 2);
  const Intersection<double> hc = intersect_quadric(make_ray<double>({-1, 0, 0}, {1, 1, 0}), cone);
  ASSERT_TRUE(hc.hit);
  EXPECT_EQ(hc.t, 0.5);
  EXPECT_FALSE(intersect_quadric(make_ray<double>({1, 0, 0}, {1, 1, 0}), cone).hit);
  // Cylinder along y, ray along y: a == b == 0, on the surface or not: miss.
  const Quadric<double> cyl = Quadric<double>::cylinder({0, 0, 0}, 1, 1, 5);
  for (const Vec3d& o : {Vec3d{1, -3, 0}, Vec3d{0.5, -3, 0}, Vec3d{2, -3, 0}}) {
    EXPECT_FALSE(intersect_quadric(make_ray(o, Vec3d{0, 1, 0}, -kInfT<double>), cyl).hit);
  }
}

TEST(QuadricProperty, HitsLieOnTheSurfaceInsideClipAndMatchOracle) {
  std::mt19937 rng(2718);
  int hits = 0, checked = 0;
  for (int i = 0; i < 20000; ++i) {
    const Shape s = kShapes[rng() % kShapes.size()];
    const int axis = int(rng() % 3);
    ShapeParams p{uniform_vec(rng, -3.0, 3.0), uniform(rng, 0.5, 2.0), uniform(rng, 0.5, 2.0),
                  uniform(rng, 0.5, 2.0), uniform(rng, 0.5, 3.0)};
    if (s == Shape::hyperboloid2) p.h = p.c + uniform(rng, 0.2, 2.0);
    const Quadric<double> q = make_shape(s, p, axis);
    const Vec3d o = uniform_vec(rng, -8.0, 8.0);
    const Vec3d target = q.clip.lo + mul(q.clip.extent(), uniform_vec(rng, 0.0, 1.0));
    RayT<double> r = make_ray(o, (target - o) * uniform(rng, 0.2, 5.0));
    if (rng() % 4 == 0) r.tnear = -kInfT<double>;
    const Intersection<double> h = intersect_quadric(r, q);
    if (h.hit) {
      ++hits;
      const Vec3d x = r.at(h.t);
      EXPECT_GE(h.t, r.tnear);
      EXPECT_LE(h.t, r.tfar);
      EXPECT_TRUE(q.clip.contains(x));
      EXPECT_LE(std::abs(q.eval(x)), 1e-9 * length(q.gradient(x)) * (length(x) + 1))
          << int(s) << " case " << i;
    }
    // Oracle: the same quadric in long double; skipped near tangency and near clip faces.
    const Quadric<L> ql = quadric_cast<L>(q);
    const RayT<L> rl{Vec3<L>(r.org), L(r.tnear), Vec3<L>(r.dir), L(r.tfar)};
    const Vec3<L> dl(r.dir);
    const L a = ql.A * dl.x * dl.x + ql.B * dl.y * dl.y + ql.C * dl.z * dl.z;
    const L b = dot(ql.gradient(rl.org), dl);
    const L c = ql.eval(rl.org);
    const L disc = b * b - 4 * a * c;
    if (std::abs(disc) < 1e-6L * b * b) continue;
    bool near_face = false;
    if (disc > 0) {
      for (L sign : {-1.0L, 1.0L}) {
        const L t_root = (-b + sign * std::sqrt(disc)) / (2 * a);
        near_face |= close_rel<L>(t_root, rl.tnear, 1e-9L);
        const Vec3<L> x = rl.at(t_root);
        for (int m = 0; m < 3; ++m) {
          near_face |= std::abs(x[m] - ql.clip.lo[m]) < 1e-7L ||
                       std::abs(x[m] - ql.clip.hi[m]) < 1e-7L;
        }
      }
    }
    if (near_face) continue;
    const Intersection<L> oracle = intersect_quadric(rl, ql);
    ++checked;
    ASSERT_EQ(h.hit, oracle.hit) << int(s) << " case " << i;
    if (h.hit) {
      EXPECT_TRUE(close_rel<L>(h.t, oracle.t, 1e-9L)) << int(s) << " case " << i;
    }
  }
  EXPECT_GE(hits, 5000);
  EXPECT_GE(checked, 10000);
}

TEST(QuadricProperty, ScalingTheDirectionByAPowerOfTwoScalesTExactly) {
  // intersect_quadric traces a power-of-two-scaled direction internally: t must scale by the
  // inverse power exactly, and extreme valid directions (core/ray.h) must not overflow.
  std::mt19937 rng(99);
  const Quadricf q = Quadricf::ellipsoid({0.5f, -0.25f, 0.0f}, {1.0f, 2.0f, 0.75f}).normalized();
  int hits = 0;
  for (int i = 0; i < 2000; ++i) {
    std::uniform_real_distribution<float> u(-4.0f, 4.0f), w(-0.5f, 0.5f);
    const Vec3f o{u(rng), u(rng), u(rng)};
    const Vec3f d = Vec3f{w(rng), w(rng), w(rng)} - o * 0.25f;
    const Ray r{o, 0.0f, d, std::numeric_limits<float>::infinity()};
    const Intersection<float> h = intersect_quadric(r, q);
    hits += h.hit;
    for (int e : {-20, -7, 3, 25}) {
      const float s = std::ldexp(1.0f, e);
      const Intersection<float> hs = intersect_quadric(Ray{o, 0.0f, d * s, r.tfar}, q);
      ASSERT_EQ(hs.hit, h.hit) << i << " 2^" << e;
      if (h.hit) {
        EXPECT_EQ(hs.t, h.t / s) << i << " 2^" << e;
      }
    }
  }
  EXPECT_GT(hits, 500);
  // b^2 of a quadric with cross terms, seen along the diagonal from 2^30 with a 2^31
  // direction, is 2^131: only the scaled direction keeps it finite.
  Quadricf cross;
  cross.A = cross.B = cross.C = cross.D = cross.E = cross.F = 1;
  cross.J = -1;
  cross.clip = {Vec3f(-2.0f), Vec3f(2.0f)};
  const Intersection<float> diagonal =
      intersect_quadric(Ray{Vec3f(0x1p30f), 0.0f, Vec3f(-0x1p31f), std::numeric_limits<float>::infinity()}, cross);
  ASSERT_TRUE(diagonal.hit);
  EXPECT_NEAR(diagonal.t, (0x1p30 - 1.0 / std::sqrt(6.0)) / 0x1p31, 1e-7);
  // At the range's corners: an origin 2^30 away, directions of largest component 2^31 and 2^-26.
  const Quadricf far = Quadricf::ellipsoid({0x1p29f, 0x1p29f, 0x1p29f}, {0x1p28f, 0x1p28f, 0x1p28f}).normalized();
  const Vec3f corner{-0x1p30f, -0x1p30f, -0x1p30f};
  for (float m : {0x1p31f, 0x1p-26f}) {
    const Vec3f dir = normalize(far.center - corner) * (m / normalize(far.center - corner).x);
    const Intersection<float> h = intersect_quadric(Ray{corner, 0.0f, dir, std::numeric_limits<float>::infinity()}, far);
    ASSERT_TRUE(h.hit) << m;
    const double expected = (length(Vec3d(far.center) - Vec3d(corner)) - 0x1p28) / length(Vec3d(dir));
    EXPECT_NEAR(h.t / expected, 1.0, 1e-5) << m;
  }
}

TEST(QuadricProperty, EqualRadiiEllipsoidMatchesSphere) {
  std::mt19937 rng(64);
  int hits = 0;
  for (int i = 0; i < 10000; ++i) {
    const SphereCase<double> s = random_sphere_case<double>(rng, i % 2);
    const SphereReference ref = sphere_reference(s);
    if (ref.tangency < 1e-6L || ref.surface < 1e-6L) continue;
    const Quadric<double> e = Quadric<double>::ellipsoid(s.c, Vec3d(s.radius));
    const Intersection<double> hq = intersect_quadric(s.ray, e);
    const Intersection<double> hs = intersect_sphere_algebraic(s.ray, s.c, s.radius);
    ASSERT_EQ(hq.hit, hs.hit) << "case " << i;
    if (!hs.hit) continue;
    ++hits;
    EXPECT_NEAR(hq.t, hs.t, 1e-8 * double(ref.scale)) << "case " << i;
  }
  EXPECT_GE(hits, 3000);
}

}  // namespace
}  // namespace rp
