// The watertight variant's triangle test (backends/simd/watertight.h): Möller–Trumbore with a
// bound on the error of each edge decision, and the exact test (rp::intersect_triangle_exact)
// where the bound leaves one uncertain. Asserted: no lane's edge decision ever differs from the
// unfiltered exact test, nor its hit or miss but where tnear or tfar lies between the two
// tests' rounded t, on rays aimed at shared edges and vertices, near them, and leaving a
// surface; the t of a hit the filter decided is as accurate as the float watertight test's
// (Woop, Benthin and Wald) against a double-precision reference; on real models only a small
// fraction of lanes needs the slow path.
// Built for AVX2+FMA with -ffp-contract=off (CMake links rp::avx2 and rp::fp_strict).

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "analysis/raygen.h"
#include "backends/simd/packet.h"
#include "backends/simd/traversal.h"
#include "backends/simd/watertight.h"
#include "base/offset.h"
#include "core/geometry/exact_triangle.h"
#include "io/loaders/load.h"
#include "tests/backends/kernel_support.h"
#include "tests/support/build_paths.h"
#include "tests/support/sanitized.h"

namespace rp::bvh8 {
namespace {

/// A closed fan of k = 3..8 triangles around a shared centre, at `scale` and moved by `shift`:
/// every corner rounded once to float, so neighbours share their vertices' floats; each
/// triangle's corners in a random cyclic order and either winding. With `flat_axis` 0, 1 or 2
/// the fan lies in a plane of constant x, y or z, as walls and floors do.
struct Fan {
  int k = 0;
  Vec3f v[3][8];
  Vec3f centre;
  Vec3f ring[8];
};

Fan make_fan(std::mt19937& rng, double scale, const Vec3d& shift, int flat_axis = -1) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Fan f;
  f.k = 3 + int(rng() % 6);
  const Vec3d c{0.2 * u(rng), 0.2 * u(rng), 0.2 * u(rng)};
  // The fan is made around z; a flat one has its z moved to the chosen axis.
  const auto place = [&](const Vec3d& p) {
    const Vec3d q = flat_axis == 0 ? Vec3d{p.z, p.x, p.y} : flat_axis == 1 ? Vec3d{p.y, p.z, p.x} : p;
    return Vec3f(q * scale + shift);
  };
  f.centre = place(c);
  for (int i = 0; i < f.k; ++i) {
    const double a = 2.0 * std::numbers::pi * (i + 0.3 * u(rng)) / f.k, r = 0.5 + 0.5 * std::abs(u(rng));
    const double z = flat_axis >= 0 ? 0.0 : 0.4 * u(rng);
    f.ring[i] = place(c + Vec3d{r * std::cos(a), r * std::sin(a), z});
  }
  for (int i = 0; i < f.k; ++i) {
    Vec3f t[3] = {f.centre, f.ring[i], f.ring[(i + 1) % f.k]};
    if (rng() & 1u) std::swap(t[1], t[2]);
    const int rot = int(rng() % 3);
    for (int j = 0; j < 3; ++j) f.v[j][i] = t[(j + rot) % 3];
  }
  return f;
}

/// A random unit direction.
Vec3d random_unit(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Vec3d d;
  do d = {n(rng), n(rng), n(rng)};
  while (dot(d, d) < 1e-6);
  return d / std::sqrt(dot(d, d));
}

/// Rays at the fan's shared centre and ring vertices, at points of its shared edges (the
/// ideal point rounded to float), at points within 2^-10..2^-30 (relative) of those, and
/// leaving its surface from the renderer's offset origin; each from a random origin at
/// 0.1..1000 times the fan's size, tfar infinite or within a few ulps of a hit's t.
std::vector<Ray> hard_rays(std::mt19937& rng, const Fan& f, double scale) {
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::vector<Ray> rays;
  for (int n = 0; n < 24; ++n) {
    const int i = int(rng() % uint32_t(f.k));
    Vec3d target;
    switch (n % 4) {
      case 0:
        target = Vec3d(f.centre);
        break;
      case 1:
        target = Vec3d(f.ring[i]);
        break;
      default: {
        const double s = u01(rng);
        target = Vec3d(f.centre) * (1.0 - s) + Vec3d(f.ring[i]) * s;
      }
    }
    if (n % 3 == 2) target = target + random_unit(rng) * (scale * std::ldexp(1.0, -10 - int(rng() % 21)));
    const double dist = scale * std::pow(10.0, -1.0 + 4.0 * u01(rng));
    const Vec3f org(target + random_unit(rng) * dist);
    const Ray r{org, 0.0f, Vec3f(target) - org, std::numeric_limits<float>::infinity()};
    if (valid_ray(r)) rays.push_back(r);  // (an origin rounded onto the target is no ray)
  }
  for (int n = 0; n < 8; ++n) {  // leaving a surface point of triangle l, towards either side
    const int l = int(rng() % uint32_t(f.k));
    const double a = u01(rng), b = u01(rng) * (1.0 - a);
    const Vec3f p(Vec3d(f.v[0][l]) * (1.0 - a - b) + Vec3d(f.v[1][l]) * a + Vec3d(f.v[2][l]) * b);
    Vec3f nrm = normalize(cross(f.v[1][l] - f.v[0][l], f.v[2][l] - f.v[0][l]));
    if (rng() & 1u) nrm = -nrm;
    Vec3d d = random_unit(rng);
    if (dot(d, Vec3d(nrm)) < 0.0) d = -d;
    rays.push_back({offset_ray_origin(p, nrm), 0.0f, Vec3f(d), std::numeric_limits<float>::infinity()});
  }
  return rays;
}

/// The lanes the kernel sends to the exact test; Möller–Trumbore's answer in `raw`.
uint32_t slow_lanes(const WatertightRays& r, const float8& tfar, const WatertightKernel::Block& b, TriHit8& raw) {
  return watertight_mt8(r, tfar, b.v0, b.e1, b.e2, b.ng, b.f, raw);
}

/// The longest |coordinate| of triangle l's edges.
double longest_edge(const Fan& f, int l) {
  double x = 0.0;
  for (int a = 0; a < 3; ++a)
    x = std::max({x, std::abs(double(f.v[0][l][a]) - double(f.v[1][l][a])),
                  std::abs(double(f.v[2][l][a]) - double(f.v[0][l][a]))});
  return x;
}

/// The exact test's answer for lane l of the fan (the unfiltered test).
Intersection<float> exact(const Ray& r, const Fan& f, int l) {
  return intersect_triangle_exact(r, f.v[0][l], f.v[1][l], f.v[2][l]);
}

/// Woop's answer for lane l of the fan (the float watertight test, for comparison).
Intersection<float> woop(const Ray& r, const Fan& f, int l) {
  return intersect_triangle_watertight(r, f.v[0][l], f.v[1][l], f.v[2][l]);
}

/// The per-lane edge bound is at least every |coordinate| of the exact edges v0 - v1 and
/// v2 - v0 (in double) and 2^-32, and within a few ulps of the largest: on triangles of every
/// size from 2^-40 to 2^30 and at every distance from the origin.
TEST(WatertightKernel, EdgeBoundCoversTheExactEdges) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  std::uniform_int_distribution<int> exponent(-40, 30);
  for (int iter = 0; iter < 20000; ++iter) {
    Vec3f v[3][8];
    const float far = std::ldexp(1.0f, exponent(rng) / 2 + 10), size = std::ldexp(1.0f, exponent(rng));
    for (int k = 0; k < 8; ++k) {
      const Vec3f c{far * unit(rng), far * unit(rng), far * unit(rng)};
      for (auto& corner : v) corner[k] = c + Vec3f{size * unit(rng), size * unit(rng), size * unit(rng)};
    }
    const std::vector<float> words = make_leaf(v[0], v[1], v[2], 8);
    const LeafView lv{Leaf(words.data())};
    alignas(32) float x[8];
    edge_bound8(lv.e1(), lv.e2()).store_aligned(x);
    for (int k = 0; k < 8; ++k) {
      double longest = 0x1p-32;
      for (int a = 0; a < 3; ++a)
        longest = std::max({longest, std::abs(double(v[0][k][a]) - double(v[1][k][a])),
                            std::abs(double(v[2][k][a]) - double(v[0][k][a]))});
      ASSERT_GE(double(x[k]), longest) << "iter " << iter << " lane " << k;
      EXPECT_LE(double(x[k]), longest * (1.0 + 0x1p-20)) << "iter " << iter << " lane " << k;
    }
  }
}

/// Every lane of the watertight test, one ray against a leaf and 8 rays against one triangle,
/// makes the exact test's edge decisions, and hits or misses exactly as the exact test does
/// unless tnear or tfar lies between the two tests' t (watertight.h: there Möller–Trumbore's t
/// decides), at translations 0..10^6 (up to 10^5 times the fan's size) and scales
/// 10^-3..10^3, with tfar infinite or tnear or tfar within ulps of a hit, and on rays leaving
/// the surface. Those lanes pass inside by both tests, and their two t differ by rounding only
/// (within 2e-4 of |t| + X / |d|; measured 1.04e-4, on lanes decided exactly, of rays nearly parallel
/// to the triangle, whose t is Möller–Trumbore's unless |den| < 2^-12 X^2 D). A hit's t is
/// Möller–Trumbore's, or for a lane decided exactly nearly in the triangle's plane the exact test's.
/// Both the filter's certain lanes and its slow path are exercised, and the certain lanes
/// include rays within 2^-12 of shared edges. The float watertight test's decisions that
/// differ from the exact ones are counted (not asserted). Under AddressSanitizer a tenth of the
/// fans: the loop's cycle of 84 scale, shift and pick cases 23 times over, each count still
/// several times its floor; the plain build runs all 20,000 with the same assertions.
TEST(WatertightKernel, NeverChangesADecisionOfTheExactTest) {
  const int fans = test::kSanitized ? 2000 : 20000;
  std::mt19937 rng(19);
  long lanes = 0, certain = 0, unsure = 0, certain_hits = 0, near_certain = 0, woop_differs = 0;
  long at_end[2] = {0, 0};  // lanes decided otherwise at tnear [0] and tfar [1]
  double widest = 0.0;      // largest |t_mt - t_exact| of those, relative to t and the edges
  for (int iter = 0; iter < fans; ++iter) {
    const double scale = std::pow(10.0, 3.0 * int(iter % 3) - 3.0);  // 1e-3, 1, 1e3
    const double shift = iter % 4 == 0 ? 0.0 : std::min(std::pow(10.0, double(iter % 7)), 1e5 * scale);
    const Fan f = make_fan(rng, scale, Vec3d{1.0, 0.75, 0.5} * shift, iter % 4 == 3 ? int(rng() % 3) : -1);
    const std::vector<float> words = make_leaf(f.v[0], f.v[1], f.v[2], uint32_t(f.k));
    const Leaf leaf(words.data());
    const LeafView lv(leaf);
    std::vector<Ray> rays = hard_rays(rng, f, scale);
    for (Ray& r : rays) {
      // tfar infinite, or tfar or tnear a few ulps either side of the nearest hit's t (the t
      // comparisons).
      if (const uint32_t pick = rng() % 6; pick < 3) {
        float t_hit = std::numeric_limits<float>::infinity();
        for (int l = 0; l < f.k; ++l)
          if (const Intersection<float> e = exact(r, f, l); e.hit) t_hit = std::min(t_hit, e.t);
        if (std::isfinite(t_hit) && t_hit > 0x1p-100f) {
          const float near_hit = std::bit_cast<float>(std::bit_cast<int32_t>(t_hit) + int32_t(rng() % 9) - 4);
          (pick == 0 ? r.tnear : r.tfar) = near_hit;
        }
      }
      const WatertightKernel::Single kernel(r);
      TriHit8 raw;
      const uint32_t slow = slow_lanes(kernel.r, float8(r.tfar), WatertightKernel::Block(lv), raw);
      const TriHit8 h = kernel.block(WatertightKernel::Block(lv), float8(r.tfar));
      for (int l = 0; l < 8; ++l) {
        if (l >= f.k) {
          ASSERT_FALSE(lane_of(h, l).hit) << "lane " << l << " past a leaf of " << f.k;
          ASSERT_FALSE(slow >> l & 1u) << "lane " << l << " past a leaf of " << f.k;
          continue;
        }
        const Intersection<float> e = exact(r, f, l);
        const Intersection<float> got = lane_of(h, l), mt = lane_of(raw, l);
        ++lanes;
        woop_differs += woop(r, f, l).hit != e.hit;
        const bool decided = slow >> l & 1u;
        unsure += decided;
        certain += !decided;
        if (!decided) {
          ASSERT_EQ(got.hit, mt.hit) << "iter " << iter << " lane " << l;
        }
        if (got.hit != e.hit) {
          // The one case where Möller–Trumbore's t decides (watertight.h): the ray passes inside
          // by both tests, and tnear or tfar lies between the two tests' t (the exact test's
          // taken over the whole line), which differ by rounding only.
          Ray open = r;
          open.tnear = -std::numeric_limits<float>::infinity();
          open.tfar = std::numeric_limits<float>::infinity();
          const Intersection<float> inside = exact(open, f, l);
          const double t_mt = mt.t, t_e = inside.t;
          const auto between = [&](double end) { return std::min(t_mt, t_e) <= end && end <= std::max(t_mt, t_e); };
          ASSERT_TRUE(inside.hit && (between(r.tnear) || between(r.tfar)))
              << "a lane decided otherwise: iter " << iter << " lane " << l << " t " << t_mt << " / " << t_e;
          const double reach = std::abs(t_e) + longest_edge(f, l) / double(max_component(abs(r.dir)));
          ASSERT_LE(std::abs(t_mt - t_e), 2e-4 * reach) << "iter " << iter << " lane " << l;
          widest = std::max(widest, std::abs(t_mt - t_e) / reach);
          ++at_end[between(r.tnear) ? 0 : 1];
          continue;
        }
        if (!got.hit) continue;
        // A hit's t is Möller–Trumbore's, or (a lane decided exactly, nearly in the plane) the exact test's.
        if (decided && got.t != mt.t) {
          expect_same_bits(got, e);
        } else {
          ASSERT_EQ(std::bit_cast<uint32_t>(got.t), std::bit_cast<uint32_t>(mt.t)) << "iter " << iter;
        }
        if (decided) continue;
        certain_hits += 1;
        // Certain although the ray passes within 2^-12 (relative) of one of the triangle's edges.
        near_certain += std::min({e.u, e.v, 1.0f - e.u - e.v}) < 0x1p-12f;
      }
    }
    // The 8-ray form, these rays against each triangle broadcast: the one-ray form's answers,
    // bit for bit.
    for (size_t first = 0; first + 8 <= rays.size(); first += 8) {
      const std::span<const Ray> eight(rays.data() + first, 8);
      RayPacket p;
      float8 tfar;
      ASSERT_EQ(load_packet(eight, p, tfar), 0xffu);
      const WatertightKernel::Packet packet(p, eight);
      for (int j = 0; j < 8; ++j) {
        const Ray& r = eight[size_t(j)];
        const TriHit8 one = WatertightKernel::Single(r).block(WatertightKernel::Block(lv), float8(r.tfar));
        for (int l = 0; l < f.k; ++l) {
          const Intersection<float> a = lane_of(
              packet.test(WatertightKernel::Triangle(WatertightKernel::Block(lv), uint32_t(l)), tfar, 0xffu), j);
          ASSERT_EQ(a.hit, lane_of(one, l).hit) << "iter " << iter << " ray " << j << " triangle " << l;
          if (a.hit) expect_same_bits(a, lane_of(one, l));
        }
      }
    }
  }
  std::printf(
      "[ certain  ] %ld of %ld lanes (%ld hits, %ld of them within 2^-12 of an edge); %ld decided exactly; "
      "decided otherwise: %ld at tnear, %ld at tfar; t apart by at most %.3g of the reach; the float watertight "
      "test decides %ld lanes otherwise than the exact test\n",
      certain, lanes, certain_hits, near_certain, unsure, at_end[0], at_end[1], widest, woop_differs);
  EXPECT_GT(at_end[0], 100);  // rays leaving a surface, decided at their own triangle
  EXPECT_GT(certain, lanes / 2);
  EXPECT_GT(certain_hits, 1000);
  EXPECT_GT(near_certain, 10);
  EXPECT_GT(unsure, 1000);
}

/// Rays from one point (a pinhole camera's): the tighter bound's factors from M taken once per
/// triangle from the packet's beam (SharedOrigin) are those of each ray's own M bit for bit, also
/// where the origin has coordinates of +0 in some lanes and -0 in others, and the packet test
/// with that bound (which decides fewer lanes exactly) gives the per-ray test's answers bit for bit;
/// rays from two points share nothing.
TEST(WatertightKernel, RaysFromOnePointShareTheirBoundAndTheirAnswers) {
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  int shared = 0, hits = 0;
  double widest_g = 0.0;  // the largest g in units of 36u X M D (R <= 2 M D)
  for (int iter = 0; iter < 3000; ++iter) {
    const double scale = std::pow(10.0, 3.0 * int(iter % 3) - 3.0);
    const double shift = iter % 4 == 0 ? 0.0 : std::min(std::pow(10.0, double(iter % 7)), 1e5 * scale);
    const Fan f = make_fan(rng, scale, Vec3d{1.0, 0.75, 0.5} * shift, iter % 4 == 3 ? int(rng() % 3) : -1);
    const std::vector<float> words = make_leaf(f.v[0], f.v[1], f.v[2], uint32_t(f.k));
    const WatertightKernel::Block kb{LeafView(Leaf(words.data()))};
    Vec3f o(Vec3d(f.centre) + random_unit(rng) * (scale * std::pow(10.0, 1.0 + 2.0 * u01(rng))));
    if (iter % 5 == 0) o[int(rng() % 3)] = 0.0f;  // an origin coordinate of 0, as +0 and -0 below
    std::vector<Ray> eight;
    for (int j = 0; j < 8; ++j) {  // towards the fan's shared vertices, edges and near them
      const int i = int(rng() % uint32_t(f.k));
      const double s = j % 3 == 0 ? 0.0 : j % 3 == 1 ? 1.0 : u01(rng);
      const Vec3d target = Vec3d(f.centre) * (1.0 - s) + Vec3d(f.ring[i]) * s +
                           random_unit(rng) * (j < 4 ? 0.0 : scale * std::ldexp(1.0, -10 - int(rng() % 21)));
      Vec3f org = o;
      for (int a = 0; a < 3; ++a)
        if (org[a] == 0.0f && (rng() & 1u)) org[a] = -0.0f;
      eight.push_back({org, 0.0f, Vec3f(target - Vec3d(o)), std::numeric_limits<float>::infinity()});
    }
    RayPacket p;
    float8 tfar;
    if (load_packet(eight, p, tfar) != 0xffu) continue;
    const PacketBeam beam(p, 0xffu);
    if (!beam.valid) continue;  // directions of mixed signs: no beam
    const SharedOrigin so(kb.v0, kb.f, OnePoint(beam));
    ASSERT_TRUE(so.shared) << "iter " << iter;
    ++shared;
    const WatertightKernel::Packet packet(p, eight);
    for (int l = 0; l < f.k; ++l) {
      const EdgeFactors fl(kb.f, l);
      const float xm = fl.xm.get(0), xx = fl.xx.get(0);
      for (const Ray& r : eight) {
        const Vec3f c = f.v[0][l] - r.org;
        const float m = std::max({std::abs(c.x), std::abs(c.y), std::abs(c.z)});  // the ray's own M
        ASSERT_EQ(std::bit_cast<uint32_t>(so.h.get(size_t(l))),
                  std::bit_cast<uint32_t>(std::fma(m, xm * (41.0f / 116.0f), xx * (54.0f / 56.0f))))
            << "iter " << iter;
        // g bounds the ray's own R term, 36u X R with R = |c x d| as the test computes it, and
        // thin its own 2^-12 X^2 D.
        const Vec3x8 rc = simd::cross_fma(Vec3x8(c), Vec3x8(r.dir));
        const float own_r = max_abs(rc).get(0), d = max_abs(Vec3x8(r.dir)).get(0);
        ASSERT_GE(so.g.get(size_t(l)), xm * (36.0f / 116.0f) * own_r) << "iter " << iter;
        ASSERT_GE(so.thin.get(size_t(l)), fl.x_thin.get(0) * d) << "iter " << iter;
        widest_g = std::max(widest_g, double(so.g.get(size_t(l))) / (double(xm) * (36.0 / 116.0) * double(m) * d));
      }
      const TriHit8 own = packet.test(WatertightKernel::Triangle(kb, uint32_t(l)), tfar, 0xffu);
      const TriHit8 once = packet.test(WatertightKernel::Triangle(kb, uint32_t(l), so), tfar, 0xffu);
      for (int j = 0; j < 8; ++j) {
        ASSERT_EQ(lane_of(once, j).hit, lane_of(own, j).hit) << "iter " << iter << " ray " << j;
        if (lane_of(own, j).hit) {
          expect_same_bits(lane_of(once, j), lane_of(own, j));
          ++hits;
        }
      }
    }
    // The same rays with one origin moved by an ulp: not one point.
    Ray& moved = eight[size_t(rng() % 8)];
    moved.org.x = std::nextafter(moved.org.x, std::numeric_limits<float>::infinity());
    ASSERT_EQ(load_packet(eight, p, tfar), 0xffu);
    const PacketBeam two(p, 0xffu);  // the same directions: as valid as `beam`
    ASSERT_TRUE(two.valid) << "iter " << iter;
    EXPECT_FALSE(SharedOrigin(kb.v0, kb.f, OnePoint(two)).shared) << "iter " << iter;
  }
  std::printf("[ one point] %d packets from one origin, %d hits compared; g at most %.3g x 36u X M D\n", shared, hits,
              widest_g);
  EXPECT_GT(shared, 1500);
  EXPECT_GT(hits, 10000);
}

/// The t of a hit the filter decided (Möller–Trumbore's) against the double-precision
/// watertight test on the same floats, beside the error of the float watertight test itself,
/// on rays at random points of random triangles at translations 0..10^6 and scales 10^-3..10^3:
/// the largest relative error stays within twice the watertight test's, the median within it.
TEST(WatertightKernel, HitDistanceIsAsAccurateAsWoopsWatertightTest) {
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::vector<double> err_kernel, err_woop;
  for (int iter = 0; iter < 4000; ++iter) {
    const double scale = std::pow(10.0, 3.0 * int(iter % 3) - 3.0);
    const double shift = iter % 4 == 0 ? 0.0 : std::min(std::pow(10.0, double(iter % 7)), 1e5 * scale);
    const Fan f = make_fan(rng, scale, Vec3d{1.0, 0.75, 0.5} * shift);
    const std::vector<float> words = make_leaf(f.v[0], f.v[1], f.v[2], uint32_t(f.k));
    const Leaf leaf(words.data());
    const int l = int(rng() % uint32_t(f.k));
    const double a = u01(rng), b = u01(rng) * (1.0 - a);
    const Vec3d target = Vec3d(f.v[0][l]) * (1.0 - a - b) + Vec3d(f.v[1][l]) * a + Vec3d(f.v[2][l]) * b;
    const Vec3f org(target + random_unit(rng) * (scale * std::pow(10.0, 3.0 * u01(rng))));
    const Ray r{org, 0.0f, Vec3f(target) - org, std::numeric_limits<float>::infinity()};
    const WatertightKernel::Single kernel(r);
    TriHit8 raw;
    const LeafView lv(leaf);
    const uint32_t slow = slow_lanes(kernel.r, float8(r.tfar), WatertightKernel::Block(lv), raw);
    const Intersection<float> w = woop(r, f, l);
    const Rayd rd{Vec3d(r.org), 0.0, Vec3d(r.dir), std::numeric_limits<double>::infinity()};
    const Intersection<double> ref =
        intersect_triangle_watertight(rd, Vec3d(f.v[0][l]), Vec3d(f.v[1][l]), Vec3d(f.v[2][l]));
    if ((slow >> l & 1u) || !w.hit || !ref.hit || !lane_of(raw, l).hit) continue;
    err_kernel.push_back(std::abs(double(lane_of(raw, l).t) - ref.t) / ref.t);
    err_woop.push_back(std::abs(double(w.t) - ref.t) / ref.t);
  }
  ASSERT_GT(err_kernel.size(), 3000u);
  const auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  const double max_c = *std::max_element(err_kernel.begin(), err_kernel.end());
  const double max_w = *std::max_element(err_woop.begin(), err_woop.end());
  std::printf("[ t error  ] %zu hits: kernel median %.3g max %.3g; Woop median %.3g max %.3g\n", err_kernel.size(),
              median(err_kernel), max_c, median(err_woop), max_w);
  EXPECT_LE(max_c, 2.0 * max_w);
  EXPECT_LE(median(err_kernel), median(err_woop));
}

/// Needles and near-degenerate triangles (as `raypack stability`'s needles family: length 2,
/// width or apex distance 10^-2..10^-7), rays from 1..10 away aimed at their centroids: the
/// kernel decides every ray as the exact test does, and its hits' t is wrong (relative error
/// beyond 1e-4 against the double-precision test on the same floats) no more often than the
/// float watertight test's. Möller–Trumbore's t alone fails there far more often (its Ng is
/// the cross product of nearly parallel edges); the guard that leaves hits with
/// |den| < 2^-12 X^2 D to the exact test, which computes t in double, is what keeps these
/// (watertight.h).
TEST(WatertightKernel, NeedleHitsAreAsAccurateAsWoopsWatertightTest) {
  std::mt19937 rng(29);
  std::uniform_real_distribution<double> u(-1.0, 1.0), u01(0.0, 1.0);
  long hits = 0, wrong_kernel = 0, wrong_woop = 0, wrong_mt = 0;
  for (int iter = 0; iter < 20000; ++iter) {
    const Vec3d axis = normalize(Vec3d{u(rng), u(rng), u(rng)});
    const Vec3d side = normalize(cross(axis, Vec3d{u(rng), u(rng), u(rng)}));
    const double width = std::pow(10.0, -2.0 - 5.0 * u01(rng));
    const Vec3d centre{3.0 * u(rng), 3.0 * u(rng), 3.0 * u(rng)};
    Vec3f v[3][8];
    v[0][0] = Vec3f(centre - axis);
    v[1][0] = Vec3f(centre + axis);
    v[2][0] = Vec3f(centre + axis * (iter % 2 ? 0.999 : 0.0) + side * width);
    const std::vector<float> words = make_leaf(v[0], v[1], v[2], 1);
    const LeafView lv{Leaf(words.data())};
    const Vec3d target = (Vec3d(v[0][0]) + Vec3d(v[1][0]) + Vec3d(v[2][0])) / 3.0;
    const Vec3f org(target + random_unit(rng) * (1.0 + 9.0 * u01(rng)));
    const Ray r{org, 0.0f, Vec3f(target) - org, std::numeric_limits<float>::infinity()};
    const Intersection<float> h =
        lane_of(WatertightKernel::Single(r).block(WatertightKernel::Block(lv), float8(r.tfar)), 0);
    const Intersection<float> w = intersect_triangle_watertight(r, v[0][0], v[1][0], v[2][0]);
    ASSERT_EQ(h.hit, intersect_triangle_exact(r, v[0][0], v[1][0], v[2][0]).hit) << "iter " << iter;
    const Rayd rd{Vec3d(r.org), 0.0, Vec3d(r.dir), std::numeric_limits<double>::infinity()};
    const Intersection<double> ref = intersect_triangle_watertight(rd, Vec3d(v[0][0]), Vec3d(v[1][0]), Vec3d(v[2][0]));
    if (!h.hit || !ref.hit) continue;
    ++hits;
    const auto wrong = [&](float t) { return std::abs(double(t) - ref.t) > 1e-4 * ref.t; };
    wrong_kernel += wrong(h.t);
    wrong_woop += wrong(w.t);
    const Intersection<float> mt = intersect_triangle_mt_normal(r, v[0][0], v[1][0], v[2][0]);
    wrong_mt += mt.hit && wrong(mt.t);
  }
  std::printf("[ needles  ] %ld hits; t beyond 1e-4: kernel %ld, Woop %ld, Moller-Trumbore alone %ld\n", hits,
              wrong_kernel, wrong_woop, wrong_mt);
  EXPECT_GT(hits, 10000);
  EXPECT_GT(wrong_mt, wrong_woop);  // the rays do find Möller–Trumbore's weakness
  EXPECT_LE(wrong_kernel, wrong_woop);
}

// --- the slow path's share on real models -----------------------------------------------------

/// Lanes tested and lanes sent to the exact test, counted by the kernel below.
struct Counts {
  uint64_t lanes = 0, slow = 0, blocks = 0, slow_blocks = 0;
};
Counts counts;

/// The watertight variant's kernel, counting what its filter leaves to the slow path.
struct CountingKernel {
  using Block = WatertightKernel::Block;
  using Triangle = WatertightKernel::Triangle;
  using Packet = WatertightKernel::Packet;
  using Origins = WatertightKernel::Origins;
  struct Single {
    WatertightKernel::Single k;
    explicit Single(const Ray& r) : k(r) {}
    Single(const RayPacket& p, int lane, const Ray& r) : k(p, lane, r) {}
    TriHit8 block(const Block& b, const float8& tfar) const {
      TriHit8 raw;
      count(b, slow_lanes(k.r, tfar, b, raw));
      return k.block(b, tfar);
    }
    TriHit8 block(const Block& b, const float8& tfar, const Origins& og) const {
      TriHit8 raw;
      count(b, og.shared ? watertight_mt8(k.r.org, k.r.dir, k.r.tnear, k.r.d, tfar, b.v0, b.e1, b.e2, b.ng, og.h, og.g,
                                          og.thin, raw)
                         : slow_lanes(k.r, tfar, b, raw));
      return k.block(b, tfar, og);
    }
    static void count(const Block& b, uint32_t slow) {
      counts.lanes += Leaf(b.leaf).n;
      counts.slow += uint64_t(std::popcount(slow));
      counts.blocks += 1;
      counts.slow_blocks += slow != 0;
    }
  };
};

/// A real model (a scene file, and the shared model it needs) and the largest share of lanes
/// its rays may send to the slow path.
struct Model {
  const char* name;
  const char* file;  ///< in the real models' folder when in_shared, else in the source tree
  bool in_shared;
  const char* needs;
  double primary, diffuse, shadow;
};

class SlowPathShare : public testing::TestWithParam<Model> {};

/// On bunny, dragon and Sponza from inside (large triangles, which the rays leaving them meet
/// at t near 0), primary rays (256 x 256) and the diffuse and shadow rays leaving their hits,
/// the share of lanes the filter leaves to the exact test (the closing figures of issue 19 come
/// from this test's output). Under 1% everywhere (a filter that also bounded the t comparisons
/// sent 4.9% of Sponza's diffuse and 8.6% of its shadow lanes) but on dragon's primary rays:
/// its triangles are about 1/2000 of the camera's distance across, and Möller–Trumbore's own
/// error (c = v0 - o errs by an ulp of that distance) is then a few thousandths of a triangle,
/// so every ray that close to an edge must be decided exactly.
TEST_P(SlowPathShare, StaysWithinItsShareOfLanes) {
  const Model& model = GetParam();
  const std::filesystem::path needs = std::filesystem::path(rp::test::kSharedScenes) / model.needs;
  if (!std::filesystem::exists(needs))
    GTEST_SKIP() << needs.string() << " is absent: the slow path's share is not measured";
  const Scene scene =
      load_scene(std::string(model.in_shared ? rp::test::kSharedScenes : rp::test::kSourceDir) + "/" + model.file);
  const Bvh8 bvh = build(scene, BuildOptions{});
  const Traversal<CountingKernel> traversal(bvh, scene);
  const RaySet primary = primary_rays(scene, 256, 256);
  std::vector<Hit> hits(primary.rays.size());
  counts = {};
  for (size_t i = 0; i < hits.size(); ++i) hits[i] = traversal.intersect_single(primary.rays[i]);
  const Counts first = counts;
  const RaySet diffuse = diffuse_rays(scene, primary, hits, 7);
  counts = {};
  for (const Ray& r : diffuse.rays) (void)traversal.intersect_single(r);
  const Counts second = counts;
  const RaySet shadow = shadow_rays(scene, primary, hits);
  counts = {};
  for (const Ray& r : shadow.rays) (void)traversal.occluded_single(r);
  const Counts third = counts;
  for (const auto& [kind, c, limit] :
       {std::tuple{"primary", first, model.primary}, std::tuple{"diffuse", second, model.diffuse},
        std::tuple{"shadow", third, model.shadow}}) {
    const double share = double(c.slow) / double(c.lanes);
    std::printf("[ slow path] %s %s: %llu of %llu lanes (%.4f%%), %.3f%% of leaf tests\n", model.name, kind,
                static_cast<unsigned long long>(c.slow), static_cast<unsigned long long>(c.lanes), 100.0 * share,
                100.0 * double(c.slow_blocks) / double(c.blocks));
    RecordProperty(std::string(kind) + "_slow_lanes_percent", std::to_string(100.0 * share));
    EXPECT_GT(c.lanes, 100000u);
    EXPECT_LT(share, limit) << kind;
  }
}

INSTANTIATE_TEST_SUITE_P(RealModels, SlowPathShare,
                         testing::Values(Model{"bunny", "bunny.obj", true, "bunny.obj", 0.01, 0.005, 0.005},
                                         Model{"dragon", "dragon.ply", true, "dragon.ply", 0.04, 0.005, 0.005},
                                         Model{"sponza_inside", "bench/scenes/sponza-inside.json", false, "sponza.obj",
                                               0.005, 0.005, 0.005}),
                         [](const testing::TestParamInfo<Model>& i) { return std::string(i.param.name); });

}  // namespace
}  // namespace rp::bvh8
