// Triangle routines against each other and long double oracles on seeded random rays; the
// Embree barycentric convention; watertightness on shared edges. The exact test's edge sides
// against 128-bit integer determinants, and its hits on rays through shared vertices and edges.

#include <gtest/gtest.h>

#include <cstdio>
#include <numbers>
#include <optional>

#include "core/geometry/exact_triangle.h"
#include "tests/support/geometry.h"

namespace rp {
namespace {

using namespace rp::test;

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

/// Whether the ray of `c` hits by the reference `ref`, or nothing when the case is too close
/// to call at this precision: conditioning below `min_det_rel`, the aim point within `margin`
/// of an edge (in barycentrics), or t within `margin` (relative) of an interval end.
template <typename T>
std::optional<bool> decisive_reference_hit(const TriangleCase<T>& c, const TriangleReference& ref, L min_det_rel,
                                           L margin) {
  if (ref.det_rel < min_det_rel) return std::nullopt;
  const L edge = std::min({std::abs(ref.b1), std::abs(ref.b2), std::abs(1 - ref.b1 - ref.b2)});
  if (edge < margin) return std::nullopt;
  if (close_rel<L>(ref.t, c.ray.tnear, margin) || close_rel<L>(ref.t, c.ray.tfar, margin)) return std::nullopt;
  return ref.b1 >= 0 && ref.b2 >= 0 && ref.b1 + ref.b2 <= 1 && ref.t >= c.ray.tnear && ref.t <= c.ray.tfar;
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
    const std::optional<bool> decisive = decisive_reference_hit(c, ref, 1e-6L, 1e-9L);
    if (!decisive) continue;
    const bool ref_hit = *decisive;
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
    const std::optional<bool> decisive = decisive_reference_hit(c, ref, 1e-2L, 1e-4L);
    if (!decisive) continue;
    const bool ref_hit = *decisive;
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

// --- the exact test (core/geometry/exact_triangle.h) -------------------------------------

/// The sign of ((p - o) x (q - o)) . d in 128-bit integers, for integer coordinates small
/// enough (|p - o|, |q - o| < 2^42, |d| < 2^21: every term below 2^106).
__extension__ using Int128 = __int128;  // (GCC's; -Wpedantic would otherwise flag it)
int integer_side(const Vec3f& p, const Vec3f& q, const Vec3f& o, const Vec3f& d) {
  Int128 a[3], b[3], e[3];
  for (int i = 0; i < 3; ++i) {
    a[i] = Int128(int64_t(p[i]) - int64_t(o[i]));
    b[i] = Int128(int64_t(q[i]) - int64_t(o[i]));
    e[i] = Int128(int64_t(d[i]));
  }
  const Int128 det =
      e[0] * (a[1] * b[2] - a[2] * b[1]) + e[1] * (a[2] * b[0] - a[0] * b[2]) + e[2] * (a[0] * b[1] - a[1] * b[0]);
  return det > 0 ? 1 : det < 0 ? -1 : 0;
}

/// edge_side is the sign of the exact determinant, checked against 128-bit integers on points
/// whose differences need up to 37 bits (beyond a float's 24, and products beyond a double's
/// 53, so the double evaluation is inexact) and on small ones: random directions, directions
/// along p - o (exactly 0) and one unit of d away from those; antisymmetric in p and q;
/// unchanged when every point is scaled by 2^k and d by 2^j, k and j in -80..80.
TEST(ExactTriangle, EdgeSideIsTheSignOfTheIntegerDeterminant) {
  std::mt19937 rng(41);
  std::uniform_int_distribution<int> small(-(1 << 20), 1 << 20), coarse(-(1 << 19), 1 << 19);
  const auto lattice = [&] {  // multiples of 2^16 below 2^35: floats, differences of up to 37 bits
    return Vec3f{std::ldexp(float(coarse(rng)), 16), std::ldexp(float(coarse(rng)), 16),
                 std::ldexp(float(coarse(rng)), 16)};
  };
  const auto scale = [](const Vec3f& v, int e) {
    return Vec3f{std::ldexp(v.x, e), std::ldexp(v.y, e), std::ldexp(v.z, e)};
  };
  int zeros = 0, units = 0, signs[3] = {0, 0, 0};
  for (int n = 0; n < 30000; ++n) {
    const bool wide = n % 2 == 1;
    Vec3f o, p, q;
    if (wide) {
      o = lattice(), p = lattice(), q = lattice();
    } else {  // small integers: the double evaluation is exact
      o = Vec3f{float(small(rng)), float(small(rng)), float(small(rng))};
      p = o + Vec3f{float(small(rng) / 2), float(small(rng) / 2), float(small(rng) / 2)};
      q = o + Vec3f{float(small(rng) / 2), float(small(rng) / 2), float(small(rng) / 2)};
    }
    Vec3f d{float(small(rng)), float(small(rng)), float(small(rng))};
    const int kind = (n / 2) % 3;  // random, along p - o (0), one unit off it
    if (kind > 0) d = wide ? scale(p - o, -16) : p - o;
    if (kind == 2) d.x += 1.0f;
    const int want = integer_side(p, q, o, d);
    ASSERT_EQ(edge_side(p, q, o, d), want) << "case " << n;
    ASSERT_EQ(edge_side(q, p, o, d), -want) << "case " << n;
    const int k = int(rng() % 161) - 80, j = int(rng() % 161) - 80;
    ASSERT_EQ(edge_side(scale(p, k), scale(q, k), scale(o, k), scale(d, j)), want) << "case " << n << " k " << k;
    zeros += want == 0;
    units += kind == 2 && want != 0;
    ++signs[want + 1];
  }
  // A NaN or infinite input gives 0 (no integer evaluation of it), whichever input it is.
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const Vec3f one{1.0f, 2.0f, 3.0f}, two{-2.0f, 1.0f, 0.5f}, zero{0.0f, 0.0f, 0.0f}, up{0.0f, 0.0f, 1.0f};
  EXPECT_EQ(edge_side(Vec3f{nan, 0.0f, 0.0f}, two, zero, up), 0);
  EXPECT_EQ(edge_side(one, Vec3f{0.0f, inf, 0.0f}, zero, up), 0);
  EXPECT_EQ(edge_side(one, two, Vec3f{0.0f, 0.0f, -inf}, up), 0);
  EXPECT_EQ(edge_side(one, two, zero, Vec3f{nan, nan, nan}), 0);
  EXPECT_NE(edge_side(one, two, zero, up), 0);
  std::printf("[ exact    ] signs -1 / 0 / +1: %d / %d / %d (%d one unit off a zero)\n", signs[0], signs[1], signs[2],
              units);
  EXPECT_GT(zeros, 9000);
  EXPECT_GT(units, 9000);
  EXPECT_GT(signs[0], 5000);
  EXPECT_GT(signs[2], 5000);
}

/// The exact test against the long double reference on random rays aimed near random
/// triangles: the same hits wherever the case is decisive (conditioning above 1e-2, the aim
/// point 1e-4 or more from the edges and t from the ends), t within 2^-22 (relative) and u, v
/// within 1e-6.
TEST(ExactTriangle, AgreesWithTheLongDoubleReference) {
  std::mt19937 rng(43);
  int checked = 0, hits = 0;
  for (int i = 0; i < 30000; ++i) {
    const TriangleCase<float> c = random_triangle_case<float>(rng);
    const TriangleReference ref = triangle_reference(c.ray, c.v0, c.v1, c.v2);
    const std::optional<bool> decisive = decisive_reference_hit(c, ref, 1e-2L, 1e-4L);
    if (!decisive) continue;
    ++checked;
    const Intersection<float> h = intersect_triangle_exact(c.ray, c.v0, c.v1, c.v2);
    ASSERT_EQ(h.hit, *decisive) << "case " << i;
    if (!h.hit) continue;
    ++hits;
    EXPECT_TRUE(close_rel<L>(h.t, ref.t, 0x1p-22L)) << "case " << i;
    EXPECT_NEAR(double(h.u), double(ref.b1), 1e-6) << "case " << i;
    EXPECT_NEAR(double(h.v), double(ref.b2), 1e-6) << "case " << i;
  }
  EXPECT_GE(checked, 10000);
  EXPECT_GE(hits, 2000);
}

/// Rays exactly through the shared centre of a closed fan, or exactly through a point of a
/// shared edge (integer coordinates, so the direction to the target is exact), from above and
/// below, translated by up to 2^22 and scaled by 2^-60..2^60 (both exact): the exact test hits
/// at least one triangle of the fan, at the target's t. The float Möller–Trumbore test misses
/// some of these (counted, not asserted).
TEST(ExactTriangle, NoRayThroughASharedVertexOrEdgeMisses) {
  std::mt19937 rng(47);
  std::uniform_int_distribution<int> coord(-64, 64);
  int rays = 0, mt_missed = 0;
  for (int n = 0; n < 3000; ++n) {
    const int e = int(rng() % 121) - 60;
    const auto place = [&](const Vec3f& v) {
      return Vec3f{std::ldexp(v.x, e), std::ldexp(v.y, e), std::ldexp(v.z, e)};
    };
    const float shift = n % 3 == 0 ? 0.0f : std::ldexp(float(coord(rng)), 16);
    const Vec3f centre{shift + 2.0f * float(coord(rng)), 2.0f * float(coord(rng)), 2.0f * float(coord(rng))};
    const int k = 4 + int(rng() % 5);
    Vec3f ring[8];
    for (int i = 0; i < k; ++i) {  // around the centre, no sector as wide as a half turn, z tilted a little
      const double a = 2.0 * std::numbers::pi * (i + 0.3 * double(rng() % 1000) / 1000.0) / k;
      ring[i] = centre + Vec3f{2.0f * float(std::round(40.0 * std::cos(a))),
                               2.0f * float(std::round(40.0 * std::sin(a))), 2.0f * float(coord(rng) / 8)};
    }
    const int i = int(rng() % uint32_t(k));
    const Vec3f target = n % 2 ? centre : centre + (ring[i] - centre) * 0.5f;  // even coordinates: exact
    const Vec3f org = target + Vec3f{float(coord(rng)), float(coord(rng)), n % 4 < 2 ? 100.0f : -100.0f};
    const Ray r = make_ray<float>(place(org), place(target) - place(org));
    int found = 0, mt_found = 0;
    for (int l = 0; l < k; ++l) {
      const Vec3f a = place(centre), b = place(ring[l]), c = place(ring[(l + 1) % k]);
      const Intersection<float> h = intersect_triangle_exact(r, a, b, c);
      if (h.hit) {
        ++found;
        EXPECT_TRUE(close_rel(h.t, 1.0f, 1e-6f)) << "case " << n << " t " << h.t;
      }
      mt_found += intersect_triangle_mt(r, a, b, c).hit;
    }
    ++rays;
    ASSERT_GT(found, 0) << "case " << n << (n % 2 ? " (vertex)" : " (edge)");
    mt_missed += mt_found == 0;
  }
  std::printf("[ exact    ] %d rays through shared vertices and edges: exact test 0 missed, Moller-Trumbore %d\n", rays,
              mt_missed);
}

}  // namespace
}  // namespace rp
