// Tests for engine/geometry: the lecture notes' worked examples with their exact answers,
// seeded random property tests against each other and against long double oracles, and the
// edge cases of the hit convention (closed [tnear, tfar], NaN never hits).

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "engine/bbox.h"
#include "engine/geometry/intersection.h"
#include "engine/geometry/plane.h"
#include "engine/geometry/polygon.h"
#include "engine/geometry/quadric.h"
#include "engine/geometry/slab.h"
#include "engine/geometry/sphere.h"
#include "engine/geometry/triangle.h"
#include "engine/math.h"
#include "engine/ray.h"

namespace rp {
namespace {

using L = long double;

template <typename T>
constexpr T kInfT = std::numeric_limits<T>::infinity();
template <typename T>
constexpr T kNanT = std::numeric_limits<T>::quiet_NaN();

template <typename T>
RayT<T> make_ray(const Vec3<T>& o, const Vec3<T>& d, T tnear = T(0), T tfar = kInfT<T>) {
  RayT<T> r;
  r.org = o;
  r.dir = d;
  r.tnear = tnear;
  r.tfar = tfar;
  return r;
}

template <typename T>
std::span<const Vec3<T>> as_span(const std::vector<Vec3<T>>& v) {
  return {v.data(), v.size()};
}

/// |a - b| <= rel * max(1, |a|, |b|); infinities are close only to themselves.
template <typename T>
bool close_rel(T a, T b, T rel) {
  if (std::isinf(a) || std::isinf(b)) return a == b;
  return std::abs(a - b) <= rel * std::max({T(1), std::abs(a), std::abs(b)});
}

template <typename T>
Vec3<T> uniform_vec(std::mt19937& rng, T lo, T hi) {
  std::uniform_real_distribution<T> u(lo, hi);
  const T x = u(rng);
  const T y = u(rng);
  const T z = u(rng);
  return {x, y, z};
}

template <typename T>
Vec3<T> unit_vec(std::mt19937& rng) {
  std::normal_distribution<T> n(T(0), T(1));
  for (;;) {
    const T x = n(rng);
    const T y = n(rng);
    const T z = n(rng);
    const Vec3<T> v{x, y, z};
    if (dot(v, v) > T(1e-6)) return normalize(v);
  }
}

template <typename T>
T uniform(std::mt19937& rng, T lo, T hi) {
  return std::uniform_real_distribution<T>(lo, hi)(rng);
}

// ---- Method tables ---------------------------------------------------------------------

template <typename T>
using TriangleFn = Intersection<T> (*)(const RayT<T>&, const Vec3<T>&, const Vec3<T>&,
                                       const Vec3<T>&);
template <typename T>
struct TriangleMethod {
  const char* name;
  TriangleFn<T> fn;
};
template <typename T>
std::array<TriangleMethod<T>, 5> triangle_methods() {
  return {{{"moller_trumbore", &intersect_triangle_mt<T>},
           {"moller_trumbore_normal", &intersect_triangle_mt_normal<T>},
           {"cramer", &intersect_triangle_cramer<T>},
           {"two_step", &intersect_triangle_two_step<T>},
           {"watertight", &intersect_triangle_watertight<T>}}};
}

template <typename T>
using SphereFn = Intersection<T> (*)(const RayT<T>&, const Vec3<T>&, T);
template <typename T>
struct SphereMethod {
  const char* name;
  SphereFn<T> fn;
};
template <typename T>
std::array<SphereMethod<T>, 3> sphere_methods() {
  return {{{"algebraic", &intersect_sphere_algebraic<T>},
           {"geometric", &intersect_sphere_geometric<T>},
           {"naive", &intersect_sphere_naive<T>}}};
}

// ---- Seed worked examples --------------------------------------------------------------

// Seeds 002, section 1 question 4: (x-2)^2/4 + (y-2)^2 + z^2/4 = 1, r(t) = t (1, 1, 0).
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

// Seeds 002, section 3 questions 2-5: box (-2,-2,-2)-(2,2,2), ray (-3,4,5) + t(1,-1,-2).
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

// Seeds 002, section 1 question 1-3: plane (p - p') . N = 0; t < 0 means no hit.
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

// Seeds 002, section 1: d . N = 0 is no hit, whether the line lies in the plane or not.
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

// Seeds 002, section 2 questions 1-2: Cramer's rule on [-D, E1, E2][t, b1, b2]^T = O - P0
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

// ---- Triangles -------------------------------------------------------------------------

struct TriangleReference {
  L det_rel;  // |det| / (|d| |e1| |e2|): sine-like conditioning of the system
  L t, b1, b2;
};

template <typename T>
TriangleReference triangle_reference(const RayT<T>& r, const Vec3<T>& v0, const Vec3<T>& v1,
                                     const Vec3<T>& v2) {
  const Vec3<L> o(r.org), d(r.dir), p0(v0), p1(v1), p2(v2);
  const Vec3<L> e1 = p1 - p0, e2 = p2 - p0, b = o - p0;
  const L det = det3_columns(-d, e1, e2);
  const L norm = length(d) * length(e1) * length(e2);
  return {std::abs(det) / norm, det3_columns(b, e1, e2) / det, det3_columns(-d, b, e2) / det,
          det3_columns(-d, e1, b) / det};
}

/// Random triangle and a ray aimed near it (barycentrics of the aim point in [-0.25, 1.25]),
/// with a random direction length and, for a quarter of the cases, a random finite interval.
template <typename T>
struct TriangleCase {
  Vec3<T> v0, v1, v2;
  RayT<T> ray;
};

template <typename T>
TriangleCase<T> random_triangle_case(std::mt19937& rng) {
  TriangleCase<T> c;
  c.v0 = uniform_vec<T>(rng, -2, 2);
  c.v1 = uniform_vec<T>(rng, -2, 2);
  c.v2 = uniform_vec<T>(rng, -2, 2);
  const Vec3<T> o = uniform_vec<T>(rng, -5, 5);
  const T b1 = uniform<T>(rng, -0.25, 1.25);
  const T b2 = uniform<T>(rng, -0.25, 1.25);
  const Vec3<T> target = c.v0 + (c.v1 - c.v0) * b1 + (c.v2 - c.v0) * b2;
  const T scale = uniform<T>(rng, 0.1, 10);
  c.ray = make_ray(o, (target - o) * scale);
  const int kind = int(rng() % 4);
  if (kind == 1) {
    c.ray.tnear = uniform<T>(rng, -0.5, 0.2) / scale;
    c.ray.tfar = uniform<T>(rng, 0.05, 2) / scale;
  } else if (kind == 2) {
    c.ray.tnear = -kInfT<T>;
  }
  return c;
}

TEST(TriangleProperty, FourMethodsAgreeOnRandomRaysDouble) {
  std::mt19937 rng(12345);
  int checked = 0, hits = 0;
  const auto methods = triangle_methods<double>();
  for (int i = 0; i < 30000; ++i) {
    const TriangleCase<double> c = random_triangle_case<double>(rng);
    const TriangleReference ref = triangle_reference(c.ray, c.v0, c.v1, c.v2);
    // Excluded: ill-conditioned systems (ray nearly parallel, sliver triangles), aim points
    // within 1e-9 of an edge, and t within 1e-9 of an interval end.
    if (ref.det_rel < 1e-6L) continue;
    const L edge = std::min({std::abs(ref.b1), std::abs(ref.b2), std::abs(1 - ref.b1 - ref.b2)});
    if (edge < 1e-9L) continue;
    if (close_rel<L>(ref.t, c.ray.tnear, 1e-9L) || close_rel<L>(ref.t, c.ray.tfar, 1e-9L)) continue;
    const bool ref_hit = ref.b1 >= 0 && ref.b2 >= 0 && ref.b1 + ref.b2 <= 1 &&
                         ref.t >= c.ray.tnear && ref.t <= c.ray.tfar;
    ++checked;
    hits += ref_hit;
    const Intersection<double> base = intersect_triangle_mt(c.ray, c.v0, c.v1, c.v2);
    for (const auto& m : methods) {
      const Intersection<double> h = m.fn(c.ray, c.v0, c.v1, c.v2);
      ASSERT_EQ(h.hit, ref_hit) << m.name << " case " << i;
      ASSERT_EQ(h.hit, base.hit) << m.name << " case " << i;
      if (!h.hit) {
        EXPECT_EQ(h.t, kInfT<double>);
        continue;
      }
      EXPECT_TRUE(close_rel<L>(h.t, ref.t, 1e-9L)) << m.name << " case " << i;
      EXPECT_TRUE(close_rel<L>(h.u, ref.b1, 1e-9L)) << m.name << " case " << i;
      EXPECT_TRUE(close_rel<L>(h.v, ref.b2, 1e-9L)) << m.name << " case " << i;
      EXPECT_TRUE(close_rel(h.t, base.t, 1e-9)) << m.name << " case " << i;
      EXPECT_TRUE(close_rel(h.u, base.u, 1e-9)) << m.name << " case " << i;
      EXPECT_TRUE(close_rel(h.v, base.v, 1e-9)) << m.name << " case " << i;
    }
  }
  EXPECT_GE(checked, 10000);
  EXPECT_GE(hits, 2000);
}

TEST(TriangleProperty, FourMethodsAgreeOnRandomRaysFloat) {
  std::mt19937 rng(777);
  int checked = 0;
  for (int i = 0; i < 30000; ++i) {
    const TriangleCase<float> c = random_triangle_case<float>(rng);
    const TriangleReference ref = triangle_reference(c.ray, c.v0, c.v1, c.v2);
    if (ref.det_rel < 1e-2L) continue;
    const L edge = std::min({std::abs(ref.b1), std::abs(ref.b2), std::abs(1 - ref.b1 - ref.b2)});
    if (edge < 1e-4L) continue;
    if (close_rel<L>(ref.t, c.ray.tnear, 1e-4L) || close_rel<L>(ref.t, c.ray.tfar, 1e-4L)) continue;
    const bool ref_hit = ref.b1 >= 0 && ref.b2 >= 0 && ref.b1 + ref.b2 <= 1 &&
                         ref.t >= c.ray.tnear && ref.t <= c.ray.tfar;
    ++checked;
    for (const auto& m : triangle_methods<float>()) {
      const Intersection<float> h = m.fn(c.ray, c.v0, c.v1, c.v2);
      ASSERT_EQ(h.hit, ref_hit) << m.name << " case " << i;
      if (!h.hit) continue;
      EXPECT_TRUE(close_rel<L>(h.t, ref.t, 1e-4L)) << m.name << " case " << i;
      EXPECT_TRUE(close_rel<L>(h.u, ref.b1, 1e-4L)) << m.name << " case " << i;
      EXPECT_TRUE(close_rel<L>(h.v, ref.b2, 1e-4L)) << m.name << " case " << i;
    }
  }
  EXPECT_GE(checked, 10000);
}

TEST(TriangleProperty, HitsLieOnTheTriangleAndInTheInterval) {
  std::mt19937 rng(99);
  int hits = 0;
  for (int i = 0; i < 20000; ++i) {
    const TriangleCase<double> c = random_triangle_case<double>(rng);
    const Vec3d n = normalize(triangle_normal(c.v0, c.v1, c.v2));
    for (const auto& m : triangle_methods<double>()) {
      const Intersection<double> h = m.fn(c.ray, c.v0, c.v1, c.v2);
      if (!h.hit) continue;
      ++hits;
      EXPECT_GE(h.t, c.ray.tnear);
      EXPECT_LE(h.t, c.ray.tfar);
      EXPECT_GE(h.u, 0.0);
      EXPECT_GE(h.v, 0.0);
      EXPECT_LE(h.u + h.v, 1.0);
      const Vec3d p = c.ray.at(h.t);
      const Vec3d q = c.v0 * (1 - h.u - h.v) + c.v1 * h.u + c.v2 * h.v;
      const double scale = length(c.ray.org) + length(c.ray.dir * h.t) + 2;
      EXPECT_LE(length(p - q), 1e-9 * scale) << m.name << " case " << i;
      EXPECT_LE(std::abs(dot(n, p - c.v0)), 1e-9 * scale) << m.name << " case " << i;
    }
  }
  EXPECT_GE(hits, 10000);
}

TEST(TriangleProperty, BarycentricsFollowEmbreeConvention) {
  const Vec3d v0{0, 0, 0}, v1{4, 0, 0}, v2{0, 4, 0};
  struct Aim {
    Vec3d p;
    double u, v;
  };
  // Interior points only: a ray aimed exactly at a vertex or edge of a lone triangle may
  // miss it by rounding (watertightness is a property of shared edges, tested below).
  for (const Aim& a : {Aim{{1, 2, 0}, 0.25, 0.5}, Aim{{2, 1, 0}, 0.5, 0.25},
                       Aim{{3.5, 0.25, 0}, 0.875, 0.0625}, Aim{{0.25, 3.5, 0}, 0.0625, 0.875},
                       Aim{{0.25, 0.25, 0}, 0.0625, 0.0625}}) {
    for (const Vec3d& o : {Vec3d{0.5, 0.25, 3}, Vec3d{-1, 2, -5}}) {
      for (const auto& m : triangle_methods<double>()) {
        const Intersection<double> h = m.fn(make_ray(o, a.p - o), v0, v1, v2);
        ASSERT_TRUE(h.hit) << m.name;
        EXPECT_NEAR(h.t, 1.0, 1e-14) << m.name;
        EXPECT_NEAR(h.u, a.u, 1e-14) << m.name;
        EXPECT_NEAR(h.v, a.v, 1e-14) << m.name;
        const Vec3d q = v0 * (1 - h.u - h.v) + v1 * h.u + v2 * h.v;
        EXPECT_LE(length(q - a.p), 1e-13) << m.name;
      }
    }
  }
  EXPECT_EQ(triangle_normal(v0, v1, v2), (Vec3d{0, 0, 16}));
}

TEST(TriangleProperty, DegenerateTriangleAndParallelRayMiss) {
  const Vec3d a{0, 0, 0}, b{1, 1, 1}, c{2, 2, 2};
  const Vec3d v0{0, 0, 0}, v1{1, 0, 0}, v2{0, 1, 0};
  for (const auto& m : triangle_methods<double>()) {
    EXPECT_FALSE(m.fn(make_ray<double>({0.5, 0.5, 3}, {-0.125, 0.25, -1}), a, b, c).hit) << m.name;
    EXPECT_FALSE(m.fn(make_ray<double>({0.1, 0.1, 0}, {1, 0, 0}), v0, v1, v2).hit) << m.name;
    EXPECT_FALSE(m.fn(make_ray<double>({0.1, 0.1, 1}, {1, 0, 0}), v0, v1, v2).hit) << m.name;
    EXPECT_FALSE(m.fn(make_ray<double>({0.1, 0.1, 1}, {0, 0, 0}), v0, v1, v2).hit) << m.name;
  }
}

// Float edge functions that round to exactly 0 are re-evaluated in double (Woop et al. 2013,
// section 3.3). Ray along +z from the origin; in 2D B = (1, 1+e), C = (-(1+e), -(1+2e)),
// e = 2^-23: cx*by - cy*bx is -e^2 exactly but 0 in float. The origin is just outside edge BC
// of ABC (A = (-1, 1)) and just inside it for DCB (D = (1, -1)): exactly one is hit.
TEST(TriangleProperty, WatertightFloatResolvesEdgeFunctionsThatRoundToZero) {
  const float e = std::ldexp(1.0f, -23);
  const Vec3f a{-1, 1, 1}, b{1, 1 + e, 1}, c{-(1 + e), -(1 + 2 * e), 1}, d{1, -1, 1};
  ASSERT_EQ(c.x * b.y - c.y * b.x, 0.0f);
  ASSERT_LT(double(c.x) * b.y - double(c.y) * b.x, 0.0);
  const Ray r = make_ray<float>({0, 0, 0}, {0, 0, 1});
  EXPECT_FALSE(intersect_triangle_watertight(r, a, b, c).hit);
  const Intersection<float> h = intersect_triangle_watertight(r, d, c, b);
  ASSERT_TRUE(h.hit);
  EXPECT_EQ(h.t, 1.0f);
}

// A closed, star-shaped mesh (a latitude/longitude sphere with random vertex radii) seen from
// near its center: every ray must hit at least one triangle, including rays aimed exactly at
// float points on shared edges and at shared vertices. That is the watertightness property.
TEST(TriangleProperty, WatertightNeverLeaksThroughSharedEdgesFloat) {
  std::mt19937 rng(4242);
  constexpr int kLat = 6, kLon = 9;
  std::vector<Vec3f> verts;
  verts.push_back({0, uniform<float>(rng, 0.8f, 1.2f), 0});  // north pole
  for (int i = 1; i < kLat; ++i) {
    for (int j = 0; j < kLon; ++j) {
      const double theta = kPi * i / kLat, phi = 2 * kPi * j / kLon;
      const float rad = uniform<float>(rng, 0.8f, 1.2f);
      verts.push_back(Vec3f(Vec3d{std::sin(theta) * std::cos(phi), std::cos(theta),
                                  std::sin(theta) * std::sin(phi)} *
                            double(rad)));
    }
  }
  verts.push_back({0, -uniform<float>(rng, 0.8f, 1.2f), 0});  // south pole
  const int south = int(verts.size()) - 1;
  const auto ring = [&](int i, int j) { return 1 + (i - 1) * kLon + (j % kLon); };
  std::vector<std::array<int, 3>> tris;
  for (int j = 0; j < kLon; ++j) tris.push_back({0, ring(1, j + 1), ring(1, j)});
  for (int i = 1; i + 1 < kLat; ++i) {
    for (int j = 0; j < kLon; ++j) {
      tris.push_back({ring(i, j), ring(i, j + 1), ring(i + 1, j)});
      tris.push_back({ring(i, j + 1), ring(i + 1, j + 1), ring(i + 1, j)});
    }
  }
  for (int j = 0; j < kLon; ++j) tris.push_back({south, ring(kLat - 1, j), ring(kLat - 1, j + 1)});

  int leaks = 0, mt_leaks = 0;
  constexpr int kRays = 20000;
  for (int n = 0; n < kRays; ++n) {
    const Vec3f o = uniform_vec<float>(rng, -0.05f, 0.05f);
    const auto& tri = tris[rng() % tris.size()];
    const Vec3f a = verts[tri[rng() % 3]];
    const Vec3f b = verts[tri[rng() % 3]];
    // Aim at a vertex (a == b) or at a float point on the edge ab.
    const float s = uniform<float>(rng, 0.0f, 1.0f);
    const Vec3f target = a + (b - a) * s;
    const Ray r = make_ray<float>(o, target - o);
    int found = 0, mt_found = 0;
    for (const auto& t : tris) {
      found += intersect_triangle_watertight(r, verts[t[0]], verts[t[1]], verts[t[2]]).hit;
      mt_found += intersect_triangle_mt(r, verts[t[0]], verts[t[1]], verts[t[2]]).hit;
    }
    leaks += found == 0;
    mt_leaks += mt_found == 0;
  }
  EXPECT_EQ(leaks, 0);
  RecordProperty("moller_trumbore_leaks", mt_leaks);
}

// ---- Spheres ---------------------------------------------------------------------------

template <typename T>
struct SphereCase {
  Vec3<T> c;
  T radius;
  RayT<T> ray;
};

/// Origin outside (kind 0), inside (kind 1) or within rounding of the surface (kind 2);
/// direction aimed within 1.3 radii of the center, random length.
template <typename T>
SphereCase<T> random_sphere_case(std::mt19937& rng, int kind) {
  SphereCase<T> s;
  s.c = uniform_vec<T>(rng, -5, 5);
  s.radius = uniform<T>(rng, 0.1, 3);
  const T dist = kind == 0 ? uniform<T>(rng, 1.01, 8) : (kind == 1 ? uniform<T>(rng, 0, 0.99) : 1);
  const Vec3<T> o = s.c + unit_vec<T>(rng) * (s.radius * dist);
  const Vec3<T> target = s.c + unit_vec<T>(rng) * (s.radius * uniform<T>(rng, 0, 1.3));
  s.ray = make_ray(o, (target - o) * uniform<T>(rng, 0.1, 10));
  if (rng() % 4 == 0) s.ray.tnear = -kInfT<T>;
  return s;
}

struct SphereReference {
  L tangency;  // |r^2 - dist^2| / r^2, small for grazing rays
  L surface;   // ||f|^2 - r^2| / r^2, small for origins on the surface
  L scale;     // (|f| + r) / |d|: the t scale of the problem
};

template <typename T>
SphereReference sphere_reference(const SphereCase<T>& s) {
  const Vec3<L> f = Vec3<L>(s.ray.org) - Vec3<L>(s.c), d(s.ray.dir);
  const L r2 = L(s.radius) * L(s.radius);
  const L a = dot(d, d), b = dot(f, d);
  const L dist2 = dot(f, f) - b * b / a;
  return {std::abs(r2 - dist2) / r2, std::abs(dot(f, f) - r2) / r2,
          (length(f) + L(s.radius)) / std::sqrt(a)};
}

TEST(SphereProperty, AlgebraicGeometricAndNaiveAgreeOnRandomRays) {
  std::mt19937 rng(31337);
  int checked = 0, hits = 0;
  for (int i = 0; i < 30000; ++i) {
    const SphereCase<double> s = random_sphere_case<double>(rng, i % 2);
    const SphereReference ref = sphere_reference(s);
    if (ref.tangency < 1e-6L || ref.surface < 1e-6L) continue;
    const Intersection<L> oracle = intersect_sphere_algebraic(
        RayT<L>{Vec3<L>(s.ray.org), s.ray.tnear, Vec3<L>(s.ray.dir), s.ray.tfar}, Vec3<L>(s.c),
        L(s.radius));
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
    const Intersection<L> oracle = intersect_sphere_algebraic(
        RayT<L>{Vec3<L>(s.ray.org), s.ray.tnear, Vec3<L>(s.ray.dir), s.ray.tfar}, Vec3<L>(s.c),
        L(s.radius));
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

// ---- Quadrics --------------------------------------------------------------------------

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
    Quadric<L> ql;
    ql.A = q.A;
    ql.B = q.B;
    ql.C = q.C;
    ql.D = q.D;
    ql.E = q.E;
    ql.F = q.F;
    ql.G = q.G;
    ql.H = q.H;
    ql.I = q.I;
    ql.J = q.J;
    ql.center = Vec3<L>(q.center);
    ql.clip = Box3<L>(Vec3<L>(q.clip.lo), Vec3<L>(q.clip.hi));
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
  // inverse power exactly, and extreme valid directions (engine/ray.h) must not overflow.
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

// ---- Slabs -----------------------------------------------------------------------------

struct SlabReference {
  bool hit;
  L t_enter, t_exit;
  L margin;  // smallest nonzero distance of a decision from flipping
};

/// Brute force in long double: clip (-inf, inf) by the six half-spaces one at a time
/// (x >= lo: t d >= lo - o; x <= hi: t d <= hi - o), no swap, no reciprocal.
template <typename T>
SlabReference slab_reference(const RayT<T>& r, const Box3<T>& b) {
  L lo_t = -std::numeric_limits<L>::infinity(), hi_t = std::numeric_limits<L>::infinity();
  bool empty = false;
  const auto clip = [&](L o, L d, L face, bool lower_face) {
    // Half-space: lower_face ? x >= face : x <= face.
    if (std::isinf(face) && ((face < 0) == lower_face)) return;  // all of space
    const L rhs = face - o;
    if (d == 0) {
      if (lower_face ? (0 < rhs) : (0 > rhs)) empty = true;
      return;
    }
    const L t = rhs / d;
    const bool t_is_lower = (d > 0) == lower_face;
    if (t_is_lower) lo_t = std::max(lo_t, t);
    else hi_t = std::min(hi_t, t);
  };
  for (int k = 0; k < 3; ++k) {
    clip(r.org[k], r.dir[k], b.lo[k], true);
    clip(r.org[k], r.dir[k], b.hi[k], false);
  }
  SlabReference ref{false, lo_t, hi_t, std::numeric_limits<L>::infinity()};
  if (empty) return ref;
  ref.hit = lo_t <= hi_t && lo_t <= L(r.tfar) && hi_t >= L(r.tnear);
  for (L m : {hi_t - lo_t, L(r.tfar) - lo_t, hi_t - L(r.tnear)}) {
    if (m != 0 && !std::isnan(m)) ref.margin = std::min(ref.margin, std::abs(m));
  }
  return ref;
}

template <typename T>
T special_or_random(std::mt19937& rng) {
  switch (rng() % 8) {
    case 0: return T(0);
    case 1: return -T(0);
    case 2: return kInfT<T>;
    case 3: return -kInfT<T>;
    case 4: return T(1);
    default: return uniform<T>(rng, -3, 3);
  }
}

template <typename T>
void check_slab_against_reference(unsigned seed, T tol) {
  std::mt19937 rng(seed);
  int checked = 0, hits = 0;
  for (int i = 0; i < 30000; ++i) {
    Vec3<T> lo = uniform_vec<T>(rng, -4, 4), hi = uniform_vec<T>(rng, -4, 4);
    Box3<T> box(min(lo, hi), max(lo, hi));
    if (rng() % 10 == 0) box.hi.x = box.lo.x;  // flat box
    Vec3<T> o = uniform_vec<T>(rng, -6, 6);
    const int where = int(rng() % 4);
    if (where == 1) o = box.lo + mul(box.extent(), uniform_vec<T>(rng, 0, 1));  // inside
    if (where == 2) {                                                            // on a face
      const int k = int(rng() % 3);
      o[k] = (rng() % 2) ? box.hi[k] : box.lo[k];
    }
    if (rng() % 10 == 0) box.lo.y = -kInfT<T>;  // unbounded face
    Vec3<T> d = uniform_vec<T>(rng, -3, 3);
    for (int k = 0; k < 3; ++k) {
      if (rng() % 3 == 0) d[k] = special_or_random<T>(rng);
    }
    RayT<T> r = make_ray(o, d);
    switch (rng() % 4) {
      case 1: r.tnear = -kInfT<T>; break;
      case 2:
        r.tnear = uniform<T>(rng, -2, 2);
        r.tfar = r.tnear + uniform<T>(rng, 0, 3);
        break;
      default: break;
    }
    const SlabHit<T> h = intersect_box(r, box);
    ASSERT_FALSE(std::isnan(h.t_enter) || std::isnan(h.t_exit)) << "case " << i;
    const SlabReference ref = slab_reference(r, box);
    const L scale = 1 + std::abs(ref.t_enter < -1e30L ? 0 : ref.t_enter) +
                    std::abs(ref.t_exit > 1e30L ? 0 : ref.t_exit);
    if (ref.margin < L(tol) * scale) continue;
    ++checked;
    hits += ref.hit;
    ASSERT_EQ(h.hit, ref.hit) << "case " << i;
    if (!h.hit) {
      EXPECT_EQ(h.t_enter, kInfT<T>);
      EXPECT_EQ(h.t_exit, -kInfT<T>);
      continue;
    }
    for (auto [got, want] : {std::pair<T, L>{h.t_enter, ref.t_enter}, {h.t_exit, ref.t_exit}}) {
      if (std::isinf(want)) {
        EXPECT_EQ(L(got), want) << "case " << i;
      } else {
        EXPECT_TRUE(close_rel<L>(got, want, L(tol))) << "case " << i << " " << got << " " << want;
      }
    }
  }
  EXPECT_GE(checked, 10000);
  EXPECT_GE(hits, 3000);
}

TEST(SlabProperty, AgreesWithBruteForceClippingReferenceFloat) {
  check_slab_against_reference<float>(1001, 1e-5f);
}

TEST(SlabProperty, AgreesWithBruteForceClippingReferenceDouble) {
  check_slab_against_reference<double>(1002, 1e-12);
}

TEST(SlabProperty, SignedZeroAndInfiniteDirectionsNeverGiveNaN) {
  const Box3f box({-1, -1, -1}, {1, 1, 1});
  const float specials[] = {0.0f, -0.0f, kInfT<float>, -kInfT<float>, 1.0f, -1.0f, 0.5f};
  const float origins[] = {-1.0f, 1.0f, 0.0f, -2.0f, 2.0f, -0.0f};  // faces, inside, outside
  int count = 0;
  for (float dx : specials) {
    for (float dy : specials) {
      for (float dz : specials) {
        for (float ox : origins) {
          for (float oy : origins) {
            const Ray r = make_ray<float>({ox, oy, 0.25f}, {dx, dy, dz});
            const SlabHit<float> h = intersect_box(r, box);
            ASSERT_FALSE(std::isnan(h.t_enter) || std::isnan(h.t_exit));
            EXPECT_EQ(h.hit, slab_reference(r, box).hit)
                << ox << "," << oy << " dir " << dx << "," << dy << "," << dz;
            ++count;
          }
        }
      }
    }
  }
  EXPECT_EQ(count, 7 * 7 * 7 * 6 * 6);
}

TEST(SlabProperty, AxisParallelRaysWithNegativeZeroComponents) {
  const Box3d box({-2, -2, -2}, {2, 2, 2});
  // Inside the y and z slabs (including exactly on their faces): hit over [1, 5] or [-5, -1].
  for (double oy : {0.0, -0.0, 2.0, -2.0}) {
    for (double dz : {0.0, -0.0}) {
      const SlabHit<double> fwd = intersect_box(make_ray<double>({-3, oy, -2}, {1, -0.0, dz}), box);
      ASSERT_TRUE(fwd.hit);
      EXPECT_EQ(fwd.t_enter, 1.0);
      EXPECT_EQ(fwd.t_exit, 5.0);
      const SlabHit<double> back =
          intersect_box(make_ray<double>({-3, oy, 2}, {-1, dz, -0.0}, -kInfT<double>), box);
      ASSERT_TRUE(back.hit);
      EXPECT_EQ(back.t_enter, -5.0);
      EXPECT_EQ(back.t_exit, -1.0);
      EXPECT_FALSE(intersect_box(make_ray<double>({-3, oy, 2}, {-1, dz, -0.0}), box).hit);
    }
  }
  // Outside a slab with a zero component: miss, for +0 and -0 alike.
  for (double dy : {0.0, -0.0}) {
    EXPECT_FALSE(intersect_box(make_ray<double>({-3, 2.5, 0}, {1, dy, 0}), box).hit);
    EXPECT_FALSE(intersect_box(make_ray<double>({-3, -2.5, 0}, {1, dy, -0.0}), box).hit);
  }
  // Origin inside, all-zero direction: the whole line is inside.
  const SlabHit<double> still = intersect_box(make_ray<double>({0, 0, 0}, {-0.0, 0, -0.0}), box);
  ASSERT_TRUE(still.hit);
  EXPECT_EQ(still.t_enter, -kInfT<double>);
  EXPECT_EQ(still.t_exit, kInfT<double>);
}

TEST(SlabProperty, RawIntervalIsNotClampedToTheRay) {
  const Box3d box({-2, -2, -2}, {2, 2, 2});
  const SlabHit<double> h = intersect_box(make_ray<double>({-3, 4, 5}, {1, -1, -2}, 2.5, 3.0), box);
  ASSERT_TRUE(h.hit);
  EXPECT_EQ(h.t_enter, 2.0);
  EXPECT_EQ(h.t_exit, 3.5);
  // Origin inside: t_enter is negative.
  const SlabHit<double> in = intersect_box(make_ray<double>({0, 0, 0}, {1, 0, 0}), box);
  ASSERT_TRUE(in.hit);
  EXPECT_EQ(in.t_enter, -2.0);
  EXPECT_EQ(in.t_exit, 2.0);
  // Box entirely behind: miss with the documented miss values.
  const SlabHit<double> miss = intersect_box(make_ray<double>({5, 0, 0}, {1, 0, 0}), box);
  EXPECT_FALSE(miss.hit);
  EXPECT_EQ(miss.t_enter, kInfT<double>);
  EXPECT_EQ(miss.t_exit, -kInfT<double>);
  // Empty default box: miss.
  EXPECT_FALSE(intersect_box(make_ray<double>({0, 0, 0}, {1, 0, 0}), Box3d{}).hit);
}

// ---- Polygons --------------------------------------------------------------------------

/// Regular star: 10 vertices alternating outer radius 2 (even index, the first at angle 0)
/// and inner radius 0.8, counter-clockwise, mapped into 3D by `place`.
template <typename F>
std::vector<Vec3d> star(F place) {
  std::vector<Vec3d> v;
  for (int i = 0; i < 10; ++i) {
    const double a = kPi / 5 * i, rad = i % 2 == 0 ? 2.0 : 0.8;
    v.push_back(place(rad * std::cos(a), rad * std::sin(a)));
  }
  return v;
}

/// Crossing count with closed y-ranges: a test ray through a vertex counts both its edges.
int naive_crossings(const std::vector<Vec3d>& v, int ax, int ay, double px, double py) {
  int n = 0;
  for (size_t i = 0, j = v.size() - 1; i < v.size(); j = i++) {
    const double xi = v[i][ax], yi = v[i][ay], xj = v[j][ax], yj = v[j][ay];
    if (yi == yj || py < std::min(yi, yj) || py > std::max(yi, yj)) continue;
    if (px < (xj - xi) * (py - yi) / (yj - yi) + xi) ++n;
  }
  return n;
}

struct PlanarFrame {
  const char* name;
  std::function<Vec3d(double, double)> place;  // 2D -> 3D point on the polygon's plane
  std::function<Rayd(double, double)> ray_at;  // ray hitting the plane at that 2D point, t = 5
};

std::vector<PlanarFrame> planar_frames() {
  return {{"z=0", [](double x, double y) { return Vec3d{x, y, 0}; },
           [](double x, double y) { return make_ray<double>({x, y, 5}, {0, 0, -1}); }},
          {"x=0", [](double x, double y) { return Vec3d{0, x, y}; },
           [](double x, double y) { return make_ray<double>({5, x, y}, {-1, 0, 0}); }}};
}

TEST(PolygonStar, KnownInsideAndOutsidePoints) {
  for (const PlanarFrame& fr : planar_frames()) {
    const std::vector<Vec3d> v = star(fr.place);
    const PolygonPlane<double> plane = polygon_plane(as_span(v));
    EXPECT_FALSE(polygon_is_convex(as_span(v)));
    const auto at_angle = [](double deg, double rad) {
      const double a = deg * kPi / 180;
      return std::array<double, 2>{rad * std::cos(a), rad * std::sin(a)};
    };
    // Inside: center, inner pentagon, every tip. Outside: notches, far away.
    for (const auto& p : {std::array<double, 2>{0.1, 0.05}, at_angle(36, 0.5), at_angle(180, 0.5),
                          at_angle(72, 1.9), at_angle(144, 1.5), at_angle(216, 1.2),
                          at_angle(288, 1.7), at_angle(0.5, 1.9)}) {
      const Intersection<double> h = intersect_polygon_even_odd(fr.ray_at(p[0], p[1]), v, plane);
      ASSERT_TRUE(h.hit) << fr.name << " " << p[0] << "," << p[1];
      EXPECT_EQ(h.t, 5.0);
      EXPECT_TRUE(intersect_polygon(fr.ray_at(p[0], p[1]), v, plane, false).hit);
    }
    for (const auto& p : {at_angle(36, 1.0), at_angle(108, 1.2), at_angle(180, 1.5),
                          at_angle(252, 0.9), at_angle(324, 1.9), std::array<double, 2>{3, 3},
                          at_angle(0, 2.5), std::array<double, 2>{-2, 0}}) {
      EXPECT_FALSE(intersect_polygon_even_odd(fr.ray_at(p[0], p[1]), v, plane).hit)
          << fr.name << " " << p[0] << "," << p[1];
    }
  }
}

TEST(PolygonStar, TestRayThroughAVertexCountsItOnce) {
  for (const PlanarFrame& fr : planar_frames()) {
    const std::vector<Vec3d> v = star(fr.place);
    const PolygonPlane<double> plane = polygon_plane(as_span(v));
    const ProjectionAxes pa = projection_axes(plane.drop_axis);
    // The scan line y = 0 passes through the tip (2, 0), where the boundary crosses it.
    // Naive closed counting sees both edges there and calls the center outside.
    for (double px : {0.0, -0.5, 1.0}) {
      EXPECT_EQ(naive_crossings(v, pa.x, pa.y, px, 0.0) % 2, 0) << "naive count is even";
      EXPECT_TRUE(intersect_polygon_even_odd(fr.ray_at(px, 0.0), v, plane).hit)
          << fr.name << " px " << px;
    }
    // Through the inner vertex at 180 degrees and the tip at 0: outside in the notch.
    EXPECT_FALSE(intersect_polygon_even_odd(fr.ray_at(-1.5, 0.0), v, plane).hit) << fr.name;
    // A local extremum: the scan line through the tip at 72 degrees only touches it.
    const double tip_y = 2 * std::sin(2 * kPi / 5);
    const double tip_x = 2 * std::cos(2 * kPi / 5);
    EXPECT_EQ(v[2][pa.y], tip_y);
    EXPECT_FALSE(intersect_polygon_even_odd(fr.ray_at(tip_x - 1, tip_y), v, plane).hit);
    // The right-most tip itself lies on the boundary; the half-open rule with a +x test ray
    // puts it outside.
    const Intersection<double> at_tip = intersect_polygon_even_odd(fr.ray_at(2.0, 0.0), v, plane);
    EXPECT_FALSE(at_tip.hit);
  }
}

// Three polygons (one non-convex) tiling the square [-2, 2]^2 and sharing the vertex (0, 0)
// and the edges from it: each shared point is inside exactly one polygon.
TEST(PolygonTiling, SharedVertexAndEdgesAreInsideExactlyOnePolygon) {
  for (const PlanarFrame& fr : planar_frames()) {
    const auto poly = [&](std::initializer_list<std::array<double, 2>> pts) {
      std::vector<Vec3d> v;
      for (const auto& p : pts) v.push_back(fr.place(p[0], p[1]));
      return v;
    };
    const std::vector<std::vector<Vec3d>> tiles = {
        poly({{-2, -2}, {2, -2}, {2, 0}, {0, 0}, {0, 2}, {-2, 2}}),  // L shape, reflex at 0
        poly({{0, 0}, {2, 0}, {2, 2}}),
        poly({{0, 0}, {2, 2}, {0, 2}})};
    EXPECT_FALSE(polygon_is_convex(as_span(tiles[0])));
    std::vector<std::array<double, 2>> shared = {{0, 0}};
    for (double s : {0.25, 0.5, 1.0, 1.5, 1.75}) {
      shared.push_back({s, 0});
      shared.push_back({0, s});
      shared.push_back({s, s});
    }
    for (const auto& p : shared) {
      int inside = 0;
      for (const auto& tile : tiles) {
        inside += intersect_polygon_even_odd(fr.ray_at(p[0], p[1]), tile,
                                             polygon_plane(as_span(tile)))
                      .hit;
      }
      EXPECT_EQ(inside, 1) << fr.name << " at " << p[0] << "," << p[1];
    }
  }
}

TEST(PolygonProperty, ConvexTestEqualsEvenOddOnConvexPolygons) {
  std::mt19937 rng(606);
  int checked = 0, hits = 0;
  for (int i = 0; i < 20000; ++i) {
    // Convex polygon on an ellipse in a random plane; angles at least 0.05 rad apart.
    const int count = 3 + int(rng() % 8);
    std::vector<double> angles;
    while (int(angles.size()) < count) {
      const double a = uniform(rng, 0.0, 2 * kPi);
      bool ok = true;
      for (double b : angles) {
        const double gap = std::abs(a - b);
        ok &= std::min(gap, 2 * kPi - gap) > 0.05;
      }
      if (ok) angles.push_back(a);
    }
    std::sort(angles.begin(), angles.end());
    if (rng() % 2) std::reverse(angles.begin(), angles.end());  // clockwise too
    const double ea = uniform(rng, 0.5, 3.0), eb = uniform(rng, 0.5, 3.0);
    const Vec3d center = uniform_vec(rng, -3.0, 3.0);
    const Vec3d normal = unit_vec<double>(rng);
    const Basis<double> basis = orthonormal_basis(normal);
    std::vector<std::array<double, 2>> local;
    std::vector<Vec3d> v;
    for (double a : angles) {
      local.push_back({ea * std::cos(a), eb * std::sin(a)});
      v.push_back(center + basis.t * local.back()[0] + basis.b * local.back()[1]);
    }
    EXPECT_TRUE(polygon_is_convex(as_span(v)));
    const PolygonPlane<double> plane = polygon_plane(as_span(v));
    // Aim point in the polygon's plane, within 1.2x its ellipse box.
    const double px = uniform(rng, -1.2, 1.2) * ea, py = uniform(rng, -1.2, 1.2) * eb;
    const Vec3d target = center + basis.t * px + basis.b * py;
    const Vec3d o = uniform_vec(rng, -8.0, 8.0);
    RayT<double> r = make_ray(o, (target - o) * uniform(rng, 0.5, 2.0));
    if (std::abs(dot(normalize(r.dir), normal)) < 1e-3) continue;
    // Truth in 2D; skip aim points within 1e-7 of an edge line.
    bool pos = false, neg = false, near_edge = false;
    for (int k = 0; k < count; ++k) {
      const auto& a = local[k];
      const auto& b = local[(k + 1) % count];
      const double ex = b[0] - a[0], ey = b[1] - a[1];
      const double s = (ex * (py - a[1]) - ey * (px - a[0])) / std::hypot(ex, ey);
      near_edge |= std::abs(s) < 1e-7;
      pos |= s > 0;
      neg |= s < 0;
    }
    if (near_edge) continue;
    const bool truth = !(pos && neg);
    ++checked;
    hits += truth;
    const Intersection<double> hc = intersect_polygon_convex(r, v, plane);
    const Intersection<double> he = intersect_polygon_even_odd(r, v, plane);
    ASSERT_EQ(hc.hit, truth) << "case " << i;
    ASSERT_EQ(he.hit, truth) << "case " << i;
    EXPECT_EQ(hc.t, he.t);
    EXPECT_EQ(intersect_polygon(r, v, plane, true).hit, truth);
    EXPECT_EQ(intersect_polygon(r, v, plane, false).hit, truth);
    if (truth) {
      const Vec3d p = r.at(hc.t);
      EXPECT_LE(std::abs(dot(plane.n, p) + plane.d) / length(plane.n), 1e-9 * (length(p) + 1));
    }
  }
  EXPECT_GE(checked, 10000);
  EXPECT_GE(hits, 3000);
}

TEST(PolygonProperty, ConvexTestIgnoresTheSignOfThePlaneNormal) {
  const std::vector<Vec3d> sq = {{-1, -1, 2}, {1, -1, 2}, {1, 1, 2}, {-1, 1, 2}};
  const PolygonPlane<double> plane = polygon_plane(as_span(sq));
  const PolygonPlane<double> flipped{-plane.n, -plane.d, plane.drop_axis};
  for (const PolygonPlane<double>& p : {plane, flipped}) {
    const Intersection<double> in = intersect_polygon_convex(
        make_ray<double>({0.5, -0.25, 0}, {0, 0, 1}), sq, p);
    ASSERT_TRUE(in.hit);
    EXPECT_EQ(in.t, 2.0);
    EXPECT_FALSE(intersect_polygon_convex(make_ray<double>({1.5, 0, 0}, {0, 0, 1}), sq, p).hit);
    EXPECT_TRUE(intersect_polygon_convex(make_ray<double>({1, 1, 0}, {0, 0, 1}), sq, p).hit);
    EXPECT_TRUE(intersect_polygon_convex(make_ray<double>({1, 0, 0}, {0, 0, 1}), sq, p).hit);
    EXPECT_TRUE(intersect_polygon_even_odd(make_ray<double>({0.5, -0.25, 0}, {0, 0, 1}), sq, p)
                    .hit);
  }
}

TEST(PolygonConvexity, DetectsConvexNonConvexAndPentagram) {
  const auto z0 = [](std::initializer_list<std::array<double, 2>> pts) {
    std::vector<Vec3d> v;
    for (const auto& p : pts) v.push_back({p[0], p[1], 0});
    return v;
  };
  EXPECT_TRUE(polygon_is_convex(as_span(z0({{0, 0}, {1, 0}, {0, 1}}))));
  EXPECT_TRUE(polygon_is_convex(as_span(z0({{0, 0}, {1, 0}, {1, 1}, {0, 1}}))));
  EXPECT_TRUE(polygon_is_convex(as_span(z0({{0, 1}, {1, 1}, {1, 0}, {0, 0}}))));  // clockwise
  EXPECT_TRUE(polygon_is_convex(as_span(z0({{0, 0}, {1, 0}, {2, 0}, {2, 2}, {0, 2}}))));
  EXPECT_FALSE(polygon_is_convex(as_span(z0({{0, 0}, {2, 0}, {1, 0.5}, {2, 2}, {0, 2}}))));
  std::vector<Vec3d> pentagram;
  for (int i = 0; i < 5; ++i) {
    const double a = 2 * kPi / 5 * ((2 * i) % 5);
    pentagram.push_back({std::cos(a), std::sin(a), 0});
  }
  EXPECT_FALSE(polygon_is_convex(as_span(pentagram)));
  EXPECT_FALSE(polygon_is_convex(as_span(z0({{0, 0}, {1, 1}, {2, 2}}))));  // degenerate
  EXPECT_FALSE(polygon_is_convex(as_span(z0({{0, 0}, {1, 1}}))));
  EXPECT_FALSE(polygon_is_convex(as_span(z0({{0, 0}, {1, 0}, {0, kNanT<double>}}))));
}

TEST(PolygonPlane, NewellNormalIsTwiceTheAreaAndDropsTheDominantAxis) {
  const std::vector<Vec3d> sq = {{0, 0, 3}, {2, 0, 3}, {2, 2, 3}, {0, 2, 3}};
  const PolygonPlane<double> p = polygon_plane(as_span(sq));
  EXPECT_EQ(p.n, (Vec3d{0, 0, 8}));
  EXPECT_EQ(p.d, -24.0);
  EXPECT_EQ(p.drop_axis, 2);
  const std::vector<Vec3d> side = {{1, 0, 0}, {1, 0, 1}, {1, 1, 1}, {1, 1, 0}};
  const PolygonPlane<double> q = polygon_plane(as_span(side));
  EXPECT_EQ(q.drop_axis, 0);
  EXPECT_EQ(q.n, (Vec3d{-2, 0, 0}));  // clockwise in (y, z): -x
  EXPECT_EQ(q.d, 2.0);
  const ProjectionAxes pa = projection_axes(1);
  EXPECT_EQ(pa.x, 2);
  EXPECT_EQ(pa.y, 0);
  // Too few vertices: zero normal, every ray misses.
  const std::vector<Vec3d> two = {{0, 0, 0}, {1, 0, 0}};
  EXPECT_EQ(polygon_plane(as_span(two)).n, Vec3d(0.0));
  EXPECT_FALSE(intersect_polygon_convex(make_ray<double>({0, 0, 1}, {0, 0, -1}), two,
                                        polygon_plane(as_span(two)))
                   .hit);
}

// ---- NaN and interval ends, for every routine ------------------------------------------

template <typename T>
struct RoutineCase {
  std::string name;
  RayT<T> ray;          // hits at t_exact (and for two-root shapes, second root t_second)
  T t_exact, t_second;  // t_second == t_exact when there is a single root
  std::function<Intersection<T>(const RayT<T>&)> run;
};

template <typename T>
std::vector<RoutineCase<T>> routine_cases() {
  std::vector<RoutineCase<T>> cases;
  const T inf = kInfT<T>;
  // Plane z = 2 and a triangle / square in it; the ray from (0.25, 0.25, 0) along +z: t = 2.
  const RayT<T> up = make_ray<T>({0.25, 0.25, 0}, {0, 0, 1});
  cases.push_back({"plane", up, 2, 2, [](const RayT<T>& r) {
                     return intersect_plane(r, Vec3<T>{0, 0, 1}, T(-2));
                   }});
  const Vec3<T> v0{0, 0, 2}, v1{1, 0, 2}, v2{0, 1, 2};
  for (const auto& m : triangle_methods<T>()) {
    cases.push_back({std::string("triangle_") + m.name, up, 2, 2,
                     [=](const RayT<T>& r) { return m.fn(r, v0, v1, v2); }});
  }
  // Sphere center (0, 0, 4) radius 2 from the origin along +z: t = 2 and 6.
  const RayT<T> s_ray = make_ray<T>({0, 0, 0}, {0, 0, 1});
  for (const auto& m : sphere_methods<T>()) {
    cases.push_back({std::string("sphere_") + m.name, s_ray, 2, 6, [=](const RayT<T>& r) {
                       return m.fn(r, Vec3<T>{0, 0, 4}, T(2));
                     }});
  }
  // Cylinder radius 2 along y from (5, 0, 0) along -x: t = 3 and 7.
  const Quadric<T> cyl = Quadric<T>::cylinder({0, 0, 0}, 2, 2, 1);
  cases.push_back({"quadric_cylinder", make_ray<T>({5, 0, 0}, {-1, 0, 0}), 3, 7,
                   [=](const RayT<T>& r) { return intersect_quadric(r, cyl); }});
  // Square polygon in z = 2.
  const std::vector<Vec3<T>> square = {{-1, -1, 2}, {1, -1, 2}, {1, 1, 2}, {-1, 1, 2}};
  const PolygonPlane<T> plane = polygon_plane(std::span<const Vec3<T>>(square));
  cases.push_back({"polygon_convex", up, 2, 2, [=](const RayT<T>& r) {
                     return intersect_polygon_convex(r, square, plane);
                   }});
  cases.push_back({"polygon_even_odd", up, 2, 2, [=](const RayT<T>& r) {
                     return intersect_polygon_even_odd(r, square, plane);
                   }});
  // Box +-2 from (-3, 0, 0) along +x: slab [1, 5]; reported through t_enter.
  const Box3<T> box({-2, -2, -2}, {2, 2, 2});
  cases.push_back({"box", make_ray<T>({-3, 0, 0}, {1, 0, 0}), 1, 1, [=](const RayT<T>& r) {
                     const SlabHit<T> h = intersect_box(r, box);
                     Intersection<T> out;
                     out.hit = h.hit;
                     out.t = h.hit ? h.t_enter : inf;
                     return out;
                   }});
  return cases;
}

template <typename T>
void check_nan_rays_miss() {
  const T nan = kNanT<T>;
  for (const RoutineCase<T>& c : routine_cases<T>()) {
    ASSERT_TRUE(c.run(c.ray).hit) << c.name;
    for (int field = 0; field < 8; ++field) {
      RayT<T> r = c.ray;
      if (field < 3) r.org[field] = nan;
      else if (field < 6) r.dir[field - 3] = nan;
      else if (field == 6) r.tnear = nan;
      else r.tfar = nan;
      const Intersection<T> h = c.run(r);
      EXPECT_FALSE(h.hit) << c.name << " NaN in field " << field;
      EXPECT_FALSE(std::isnan(h.t)) << c.name << " NaN in field " << field;
    }
  }
}

TEST(NanInputs, NanInAnyRayComponentNeverHitsDouble) { check_nan_rays_miss<double>(); }
TEST(NanInputs, NanInAnyRayComponentNeverHitsFloat) { check_nan_rays_miss<float>(); }

TEST(NanInputs, NanInThePrimitiveNeverHits) {
  const double nan = kNanT<double>;
  const Rayd up = make_ray<double>({0.25, 0.25, 0}, {0, 0, 1});
  EXPECT_FALSE(intersect_plane(up, Vec3d{0, nan, 1}, -2.0).hit);
  EXPECT_FALSE(intersect_plane(up, Vec3d{0, 0, 1}, nan).hit);
  for (int k = 0; k < 9; ++k) {
    Vec3d v[3] = {{0, 0, 2}, {1, 0, 2}, {0, 1, 2}};
    v[k / 3][k % 3] = nan;
    for (const auto& m : triangle_methods<double>()) {
      EXPECT_FALSE(m.fn(up, v[0], v[1], v[2]).hit) << m.name << " vertex field " << k;
    }
    for (const auto& m : triangle_methods<float>()) {
      Vec3f vf[3] = {Vec3f(v[0]), Vec3f(v[1]), Vec3f(v[2])};
      const Ray rf = make_ray<float>({0.25f, 0.25f, 0}, {0, 0, 1});
      EXPECT_FALSE(m.fn(rf, vf[0], vf[1], vf[2]).hit) << m.name << " vertex field " << k;
    }
  }
  const Rayd s_ray = make_ray<double>({0, 0, 0}, {0, 0, 1});
  for (const auto& m : sphere_methods<double>()) {
    EXPECT_FALSE(m.fn(s_ray, Vec3d{0, 0, 4}, nan).hit) << m.name;
    EXPECT_FALSE(m.fn(s_ray, Vec3d{nan, 0, 4}, 2.0).hit) << m.name;
    EXPECT_FALSE(m.fn(s_ray, Vec3d{0, 0, nan}, 2.0).hit) << m.name;
  }
  Quadric<double> cyl = Quadric<double>::cylinder({0, 0, 0}, 2, 2, 1);
  const Rayd q_ray = make_ray<double>({5, 0, 0}, {-1, 0, 0});
  for (double Quadric<double>::*coef :
       {&Quadric<double>::A, &Quadric<double>::B, &Quadric<double>::C, &Quadric<double>::D,
        &Quadric<double>::E, &Quadric<double>::F, &Quadric<double>::G, &Quadric<double>::H,
        &Quadric<double>::I, &Quadric<double>::J}) {
    Quadric<double> q = cyl;
    q.*coef = nan;
    EXPECT_FALSE(intersect_quadric(q_ray, q).hit);
  }
  cyl.clip.lo.y = nan;
  EXPECT_FALSE(intersect_quadric(q_ray, cyl).hit);
  Box3d box({-2, -2, -2}, {2, 2, 2});
  box.hi.z = nan;
  const SlabHit<double> bh = intersect_box(make_ray<double>({-3, 0, 0}, {1, 0, 0}), box);
  EXPECT_FALSE(bh.hit);
  EXPECT_FALSE(std::isnan(bh.t_enter) || std::isnan(bh.t_exit));
  std::vector<Vec3d> square = {{-1, -1, 2}, {1, -1, 2}, {1, 1, 2}, {-1, 1, 2}};
  square[2].x = nan;
  const PolygonPlane<double> plane = polygon_plane(as_span(square));
  EXPECT_FALSE(intersect_polygon_convex(up, square, plane).hit);
  EXPECT_FALSE(intersect_polygon_even_odd(up, square, plane).hit);
}

template <typename T>
void check_interval_ends() {
  const T inf = kInfT<T>;
  for (const RoutineCase<T>& c : routine_cases<T>()) {
    const T t = c.t_exact;
    const auto with = [&](T tnear, T tfar) {
      RayT<T> r = c.ray;
      r.tnear = tnear;
      r.tfar = tfar;
      return c.run(r);
    };
    // A hit exactly at tnear or exactly at tfar is accepted, with that exact t.
    const Intersection<T> at_near = with(t, inf);
    ASSERT_TRUE(at_near.hit) << c.name;
    EXPECT_EQ(at_near.t, t) << c.name;
    const Intersection<T> at_far = with(T(0), t);
    ASSERT_TRUE(at_far.hit) << c.name;
    EXPECT_EQ(at_far.t, t) << c.name;
    const Intersection<T> point = with(t, t);
    ASSERT_TRUE(point.hit) << c.name;
    EXPECT_EQ(point.t, t) << c.name;
    // One ulp before the hit: rejected.
    EXPECT_FALSE(with(T(0), std::nextafter(t, T(0))).hit) << c.name;
    // One ulp past the first root: the second root if there is one, else a miss
    // (the box's entry t_enter = 1 stays the raw value while the interval still overlaps).
    const Intersection<T> past = with(std::nextafter(t, inf), inf);
    if (c.name == "box") {
      ASSERT_TRUE(past.hit);
      EXPECT_EQ(past.t, t);
      EXPECT_TRUE(with(T(5), inf).hit);
      EXPECT_FALSE(with(std::nextafter(T(5), inf), inf).hit);
    } else if (c.t_second != t) {
      ASSERT_TRUE(past.hit) << c.name;
      EXPECT_EQ(past.t, c.t_second) << c.name;
      EXPECT_TRUE(with(c.t_second, c.t_second).hit) << c.name;
      EXPECT_FALSE(with(std::nextafter(c.t_second, inf), inf).hit) << c.name;
    } else {
      EXPECT_FALSE(past.hit) << c.name;
    }
  }
}

TEST(IntervalEnds, HitExactlyAtTnearOrTfarIsAcceptedAndJustOutsideIsNotDouble) {
  check_interval_ends<double>();
}

TEST(IntervalEnds, HitExactlyAtTnearOrTfarIsAcceptedAndJustOutsideIsNotFloat) {
  check_interval_ends<float>();
}

TEST(IntervalEnds, HitAtInfinityIsNotReported) {
  // Direction so short that t overflows: the plane is hit "at infinity", which is a miss.
  const Rayd r = make_ray<double>({0, 0, 0}, {0, 0, 1e-310});
  EXPECT_FALSE(intersect_plane(r, Vec3d{0, 0, 1}, -1e10).hit);
  EXPECT_FALSE(in_ray_interval(make_ray<double>({0, 0, 0}, {1, 0, 0}), kInfT<double>));
  EXPECT_TRUE(in_ray_interval(make_ray<double>({0, 0, 0}, {1, 0, 0}), 0.0));
}

}  // namespace
}  // namespace rp
