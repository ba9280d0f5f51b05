// The queries beyond closest and any hit (core/queries.h), on every variant of both backends,
// against brute force in double and the double reference (analysis/reference.h): closest
// points, inside and signed distance, counts and every hit along a ray, masks, filters and
// geometry ids.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <span>
#include <string>
#include <tuple>
#include <vector>

#include "analysis/reference.h"
#include "backends/registry.h"
#include "core/queries.h"
#include "tests/support/error_of.h"
#include "tests/support/grid_scenes.h"
#include "tests/support/scenes.h"
#include "tests/support/variants.h"

namespace rp {
namespace {

std::unique_ptr<Backend> build(const TraceMethod& m, const Scene& s) {
  BackendOptions o;
  o.variant = m.variant;
  return make_backend(m.backend, s, o);
}

// ---- brute force in double ----

/// Distance from p to segment [a, b].
double segment_distance(const Vec3d& p, const Vec3d& a, const Vec3d& b) {
  const Vec3d ab = b - a;
  const double len2 = dot(ab, ab);
  const double s = len2 > 0 ? std::clamp(dot(p - a, ab) / len2, 0.0, 1.0) : 0.0;
  return length(p - (a + ab * s));
}

/// Distance from p to triangle (a, b, c): to its plane when p projects inside it (signs of
/// the three edge tests), else to its nearest edge. Independent of Ericson's regions.
double triangle_distance(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d n = cross(b - a, c - a);
  const double n2 = dot(n, n);
  const double edges = std::min({segment_distance(p, a, b), segment_distance(p, b, c), segment_distance(p, c, a)});
  if (n2 == 0) return edges;
  const Vec3d q = p - n * (dot(n, p - a) / n2);
  const bool inside =
      dot(cross(b - a, q - a), n) >= 0 && dot(cross(c - b, q - b), n) >= 0 && dot(cross(a - c, q - c), n) >= 0;
  return inside ? std::abs(dot(n, p - a)) / std::sqrt(n2) : edges;
}

/// A world triangle in double: its corners (an instance's mapped in double), prim and instance.
struct TriangleD {
  Vec3d v[3];
  uint32_t prim, inst;
};

std::vector<TriangleD> world_triangles(const Scene& s) {
  std::vector<TriangleD> out;
  for (size_t m = 0; m < s.meshes().size(); ++m) {
    const MeshView& mesh = s.meshes()[m];
    auto add = [&](const Affine3d* place, uint32_t inst) {
      for (uint32_t t = 0; t < mesh.triangle_count(); ++t) {
        TriangleD d{{}, s.mesh_base(m) + t, inst};
        for (int j = 0; j < 3; ++j) {
          const Vec3d v(mesh.vertex(t, j));
          d.v[j] = place ? place->point(v) : v;
        }
        out.push_back(d);
      }
    };
    if (!s.is_instanced(m)) add(nullptr, kNoInstance);
    for (uint32_t i = 0; i < s.instances().size(); ++i)
      if (s.instances()[i].mesh == m) {
        const Affine3d w(s.instances()[i].object_to_world);
        add(&w, i);
      }
  }
  return out;
}

/// The distance from p to the scene's surface (triangles, spheres, planes), brute force.
double surface_distance(const Scene& s, const std::vector<TriangleD>& tris, const Vec3d& p) {
  double d = std::numeric_limits<double>::infinity();
  for (const TriangleD& t : tris) d = std::min(d, triangle_distance(p, t.v[0], t.v[1], t.v[2]));
  for (const Sphere& sp : s.spheres()) d = std::min(d, std::abs(length(p - Vec3d(sp.center)) - double(sp.radius)));
  for (const Plane& pl : s.planes()) {
    const Vec3d n(pl.normal);
    d = std::min(d, std::abs(dot(n, p) + double(pl.d)) / length(n));
  }
  return d;
}

/// The distance from p to primitive `prim` as placed by `inst`, brute force.
double prim_distance(const Scene& s, const std::vector<TriangleD>& tris, uint32_t prim, uint32_t inst, const Vec3d& p) {
  for (const TriangleD& t : tris)
    if (t.prim == prim && t.inst == inst) return triangle_distance(p, t.v[0], t.v[1], t.v[2]);
  const PrimLocation at = s.locate(prim);
  if (at.kind == PrimKind::sphere) {
    const Sphere& sp = s.spheres()[at.shape];
    return std::abs(length(p - Vec3d(sp.center)) - double(sp.radius));
  }
  const Plane& pl = s.planes()[at.shape];
  return std::abs(dot(Vec3d(pl.normal), p) + double(pl.d)) / length(Vec3d(pl.normal));
}

/// Generalised winding number of closed triangle set `tris` at p (van Oosterom and Strackee's
/// solid angle of each triangle, summed, over 4 pi): about 1 inside, 0 outside.
double winding_number(const std::vector<TriangleD>& tris, const Vec3d& p) {
  double sum = 0;
  for (const TriangleD& t : tris) {
    const Vec3d a = t.v[0] - p, b = t.v[1] - p, c = t.v[2] - p;
    const double la = length(a), lb = length(b), lc = length(c);
    const double num = dot(a, cross(b, c));
    const double den = la * lb * lc + dot(a, b) * lc + dot(b, c) * la + dot(c, a) * lb;
    sum += 2 * std::atan2(num, den);
  }
  return sum / (4 * kPi);
}

/// A closed tessellated sphere placed twice (once stretched unevenly), a world mesh, an
/// analytic sphere and a plane: what closest points answer (no quadric).
Scene point_scene() {
  Scene s = test::instanced_scene();
  s.remove_quadric(0);
  return s;
}

std::vector<Vec3f> random_points(uint32_t seed, int n, float half) {
  std::mt19937 rng(seed);
  std::vector<Vec3f> out;
  for (int i = 0; i < n; ++i) out.push_back(test::random_in_box(rng, -half, half));
  return out;
}

// ---- closest points ----

TEST(Queries, ClosestPointsAreTheBruteForceOnesOnEveryBackend) {
  const Scene s = point_scene();
  const std::vector<TriangleD> tris = world_triangles(s);
  const std::vector<Vec3f> points = random_points(7, 400, 2.5f);
  std::vector<PointQuery> queries;
  for (const Vec3f& p : points) queries.push_back({p});
  const double extent = 3.0, tol = 1e-5 * extent;
  std::vector<ClosestPoint> first;
  for (const TraceMethod& m : test::backend_variants()) {
    SCOPED_TRACE(m.backend + "/" + m.variant);
    const auto b = build(m, s);
    std::vector<ClosestPoint> got(queries.size());
    b->closest_points(queries, got);
    for (size_t i = 0; i < points.size(); ++i) {
      const Vec3d p(points[i]);
      ASSERT_TRUE(got[i].found());
      const double truth = surface_distance(s, tris, p);
      EXPECT_NEAR(got[i].distance, truth, tol) << "point " << i;
      // The point is on the primitive named, at the distance given.
      EXPECT_LT(prim_distance(s, tris, got[i].prim_id, got[i].instance_id, Vec3d(got[i].point)), tol) << i;
      EXPECT_NEAR(length(Vec3d(got[i].point) - p), got[i].distance, tol) << i;
    }
    if (first.empty()) {
      first = got;
      continue;
    }
    for (size_t i = 0; i < points.size(); ++i) {  // every backend computes the same point
      EXPECT_EQ(got[i].prim_id, first[i].prim_id) << i;
      EXPECT_EQ(got[i].instance_id, first[i].instance_id) << i;
      EXPECT_EQ(got[i].distance, first[i].distance) << i;
    }
  }
}

TEST(Queries, ARadiusLimitsTheSearchAndBadQueriesFindNothing) {
  const Scene s = point_scene();
  const std::vector<TriangleD> tris = world_triangles(s);
  const std::vector<Vec3f> points = random_points(8, 100, 2.5f);
  for (const TraceMethod& m : test::backend_variants()) {
    SCOPED_TRACE(m.backend + "/" + m.variant);
    const auto b = build(m, s);
    std::vector<PointQuery> q;
    for (const Vec3f& p : points) q.push_back({p, 0.1f});
    q.push_back({{std::nanf(""), 0.0f, 0.0f}});
    q.push_back({{0.0f, 0.0f, 0.0f}, -1.0f});
    q.push_back({{0.0f, 0.0f, 0.0f}, std::nanf("")});
    std::vector<ClosestPoint> got(q.size());
    b->closest_points(q, got);
    for (size_t i = 0; i < points.size(); ++i) {
      const double truth = surface_distance(s, tris, Vec3d(points[i]));
      if (truth > 0.1 + 1e-5) {
        EXPECT_FALSE(got[i].found()) << i;
      }
      if (truth < 0.1 - 1e-5) {
        EXPECT_TRUE(got[i].found()) << i;
      }
    }
    for (size_t i = points.size(); i < q.size(); ++i) {
      EXPECT_FALSE(got[i].found());
      EXPECT_EQ(got[i].distance, std::numeric_limits<float>::infinity());
    }
  }
}

TEST(Queries, ClosestPointsRefuseQuadricsAndAStaleBackend) {
  Scene s = test::instanced_scene();
  for (const TraceMethod& m : test::backend_variants()) {
    const auto b = build(m, s);
    std::vector<PointQuery> q{{{0.0f, 0.0f, 0.0f}}};
    std::vector<ClosestPoint> out(1);
    EXPECT_EQ(test::error_of([&] { b->closest_points(q, out); }),
              m.backend + ": closest points: the scene has 1 quadric (quadrics have no closest-point routine)");
  }
  s.remove_quadric(0);
  const auto b = make_backend("simd", s);
  s.add_sphere({{3.0f, 0.0f, 0.0f}, 0.5f, 0});
  std::vector<PointQuery> q{{{0.0f, 0.0f, 0.0f}}};
  std::vector<ClosestPoint> out(1);
  EXPECT_NE(test::error_of([&] { b->closest_points(q, out); }).find("call update() before tracing"), std::string::npos);
  b->update();
  b->closest_points(q, out);
  EXPECT_TRUE(out[0].found());
}

TEST(Queries, ClosestPointsAreTheDoubleReferencesOnEveryBackend) {
  // Instances (rotated, scaled unevenly, mirrored), a world mesh, a sphere, a polygon and a
  // plane; then the grid scene, whose exact duplicates tie. A third of the queries have a
  // radius: found or not as the reference, but where the distance is within tolerance of it.
  const Scene scenes[] = {test::without_quadrics(test::instanced_scene_with_polygon()),
                          test::without_quadrics(test::random_scene(3, 300, {0, 0, 0}))};
  for (const Scene& s : scenes) {
    const Reference reference(s);
    const double extent = max_component(s.bounds().extent()), tol = 1e-5 * extent;
    std::mt19937 rng(17);
    std::vector<PointQuery> q;
    for (const Vec3f& p : random_points(17, 600, float(0.6 * extent)))
      q.push_back({p, rng() % 3 ? std::numeric_limits<float>::infinity() : test::uniform(rng, 0.0f, 0.5f)});
    std::vector<ReferencePoint> want(q.size());
    reference.closest_points(q, want);
    size_t found = 0;
    for (const ReferencePoint& w : want) found += w.found();
    EXPECT_GT(3 * found, 2 * q.size());
    for (const TraceMethod& m : test::backend_variants()) {
      SCOPED_TRACE(m.backend + "/" + m.variant);
      std::vector<ClosestPoint> got(q.size());
      build(m, s)->closest_points(q, got);
      for (size_t i = 0; i < q.size(); ++i) {
        if (got[i].found() != want[i].found()) {  // only where the distance is the radius
          EXPECT_NEAR(want[i].found() ? want[i].distance : double(got[i].distance), q[i].radius, tol) << i;
          continue;
        }
        if (want[i].found()) {
          EXPECT_NEAR(got[i].distance, want[i].distance, tol) << "point " << i;
        }
      }
    }
  }
}

// ---- inside, signed distance ----

TEST(Queries, SignedDistanceHasTheWindingNumbersSignAwayFromTheSurface) {
  // A closed mesh placed twice (once mirrored) beside a world copy: the inside is the union.
  const Scene ball = test::tessellated_sphere(32, 16);
  Scene s;
  const uint32_t b = s.add_instanced_mesh(ball.meshes()[0]);
  // Disjoint shapes: the inside of each is where its winding number is +-1 (the mirrored one
  // winds the other way).
  s.add_instance(b, test::placement({0.5f, 0.35f, 0.45f}, {1, 1, 0}, 30.0f, {-0.7f, 0.0f, 0.0f}));
  s.add_instance(b, test::placement({-0.45f, 0.45f, 0.45f}, {0, 0, 1}, 10.0f, {0.8f, 0.0f, 0.2f}));
  TriangleMesh world = to_triangle_mesh(ball.meshes()[0]);
  for (Vec3f& p : world.positions) p = p * 0.3f + Vec3f(0.0f, 1.1f, 0.0f);
  s.add_mesh(world);
  s.add_sphere({{0.0f, -1.0f, 0.0f}, 0.35f, 0});
  const std::vector<TriangleD> tris = world_triangles(s);
  std::vector<std::vector<TriangleD>> shapes(3);  // instance 0, instance 1, the world mesh
  for (const TriangleD& t : tris) shapes[std::min<uint32_t>(t.inst, 2)].push_back(t);
  const std::vector<Vec3f> points = random_points(9, 1000, 1.4f);
  const double extent = 3.2;
  std::vector<double> distance(points.size());
  std::vector<uint8_t> in(points.size());
  size_t inside_points = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    const Vec3d p(points[i]);
    distance[i] = surface_distance(s, tris, p);
    const Sphere& sp = s.spheres()[0];
    in[i] = length(p - Vec3d(sp.center)) < sp.radius;
    for (const std::vector<TriangleD>& shape : shapes) in[i] |= std::abs(winding_number(shape, p)) > 0.5;
    inside_points += in[i] && distance[i] > 1e-3 * extent;
  }
  EXPECT_GT(inside_points, 30u);  // the test sees both sides
  for (const TraceMethod& m : test::backend_variants()) {
    SCOPED_TRACE(m.backend + "/" + m.variant);
    const auto bk = build(m, s);
    std::vector<float> sd(points.size());
    signed_distance(*bk, points, sd);
    for (size_t i = 0; i < points.size(); ++i) {
      EXPECT_NEAR(std::abs(sd[i]), distance[i], 1e-5 * extent) << i;
      if (distance[i] > 1e-3 * extent) {
        EXPECT_EQ(sd[i] < 0, bool(in[i])) << "point " << i << " at distance " << distance[i];
      }
    }
  }
}

// ---- counts and every hit ----

/// True when a backend's hits of one ray are the reference's: the same primitives in the same
/// placements, each t within 1e-4 of the reference's (relative to max(1, t)). Triangles' and
/// spheres' float t are within a few float roundings of it, but a quadric's float roots, taken
/// from coefficients rounded to float, lose digits where a ray nearly grazes it (two roots
/// close together, whose error grows as they approach); 1e-4 covers that on these rays and
/// still tells two crossings apart. Both sides are compared sorted by (prim_id, instance_id,
/// t): two hits whose float t round alike may come in either order by t.
bool same_hits(std::span<const Hit> got, std::span<const ReferenceHit> want) {
  if (got.size() != want.size()) return false;
  std::vector<Hit> g(got.begin(), got.end());
  std::vector<ReferenceHit> w(want.begin(), want.end());
  std::sort(g.begin(), g.end(), [](const Hit& a, const Hit& b) {
    return std::tie(a.prim_id, a.instance_id, a.t) < std::tie(b.prim_id, b.instance_id, b.t);
  });
  std::sort(w.begin(), w.end(), [](const ReferenceHit& a, const ReferenceHit& b) {
    return std::tie(a.prim_id, a.instance_id, a.t) < std::tie(b.prim_id, b.instance_id, b.t);
  });
  for (size_t k = 0; k < g.size(); ++k)
    if (g[k].prim_id != w[k].prim_id || g[k].instance_id != w[k].instance_id ||
        std::abs(double(g[k].t) - w[k].t) > 1e-4 * std::max(1.0, w[k].t))
      return false;
  return true;
}

/// Counts and every hit of each backend against the double reference on `rays` through `s`: at
/// most one ray in 300 may differ (a ray through an edge or a vertex, where the default
/// variants decide each triangle on its own, or a hit at a clip boundary or an interval end
/// that float and double place on either side), and the lists sorted by t, max_per_ray their
/// prefixes, the counts their sizes.
void expect_every_hit_is_the_references(const Scene& s, const std::vector<Ray>& rays, const char* what) {
  const Reference reference(s);
  const ReferenceHitList want = reference.all_hits(rays);
  const size_t crossings = want.hits.size();
  for (const TraceMethod& m : test::backend_variants()) {
    SCOPED_TRACE(m.backend + "/" + m.variant + " " + what);
    const auto b = build(m, s);
    std::vector<uint32_t> counts(rays.size());
    b->count_hits(rays, counts);
    const HitList all = b->all_hits(rays);
    const HitList two = b->all_hits(rays, 2);
    size_t off = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
      ASSERT_EQ(counts[i], all.count(i));
      EXPECT_EQ(two.count(i), std::min<size_t>(2, all.count(i)));
      for (size_t k = 0; k < all.count(i); ++k) {
        if (k) {
          EXPECT_LE(all.of(i)[k - 1].t, all.of(i)[k].t) << i;
        }
        if (k < two.count(i)) {
          EXPECT_EQ(two.of(i)[k].prim_id, all.of(i)[k].prim_id) << i;
        }
      }
      off += !same_hits(all.of(i), want.of(i));
    }
    EXPECT_LE(off * 300, rays.size()) << off << " rays whose hits differ from the reference's";
  }
  EXPECT_GT(2 * crossings, rays.size()) << what;
}

TEST(Queries, CountsAndEveryHitAreTheDoubleReferencesOnEveryBackend) {
  // Instances (rotated, scaled unevenly, mirrored), a world mesh, a sphere, a quadric, a
  // polygon and a plane; then the grid scene (exact duplicates, faces on the grid) with random
  // rays through it.
  expect_every_hit_is_the_references(test::instanced_scene_with_polygon(), test::random_rays(11, 1200), "instances");
  std::vector<Ray> rays = test::random_rays(12, 1200);
  for (Ray& r : rays) r = {r.org * 1.6f, r.tnear, r.dir * 1.6f, r.tfar};  // the grid scene spans [-3, 3]
  expect_every_hit_is_the_references(test::random_scene(3, 300, {0, 0, 0}), rays, "grid_scene");
}

TEST(Queries, EveryHitOfAClosedMeshComesInPairs) {
  // A ray from outside a closed mesh crosses it an even number of times; inside, odd.
  const Scene s = test::tessellated_sphere(24, 12);
  std::mt19937 rng(3);
  std::vector<Ray> rays;
  for (int i = 0; i < 300; ++i)
    rays.push_back({test::random_in_box(rng, -0.5f, 0.5f), 0.0f, test::random_direction(rng)});
  for (int i = 0; i < 300; ++i) {
    const Vec3f o = test::random_direction(rng) * 3.0f;
    rays.push_back({o, 0.0f, test::random_in_box(rng, -0.5f, 0.5f) - o});  // through the inside
  }
  for (const TraceMethod& m : test::backend_variants()) {
    SCOPED_TRACE(m.backend + "/" + m.variant);
    const auto b = build(m, s);
    std::vector<uint32_t> counts(rays.size());
    b->count_hits(rays, counts);
    size_t wrong = 0;
    for (size_t i = 0; i < rays.size(); ++i) wrong += counts[i] != (i < 300 ? 1u : 2u);
    EXPECT_LE(wrong * 300, rays.size()) << wrong;
  }
}

// ---- masks, filters, geometry ids ----

/// Two meshes side by side: a soup (geometry 0) and a tessellated sphere (geometry 1).
Scene two_meshes() {
  Scene s;
  s.add_mesh(test::triangle_soup(5, 200).meshes()[0]);
  TriangleMesh ball = to_triangle_mesh(test::tessellated_sphere(16, 8).meshes()[0]);
  for (Vec3f& p : ball.positions) p = p * 0.6f + Vec3f(0.3f, 0.2f, 0.1f);
  s.add_mesh(ball);
  return s;
}

TEST(Queries, RayMasksHideGeometriesAsEmbreeDoes) {
  Scene s = two_meshes();
  s.set_mask(0, 0b01);
  s.set_mask(1, 0b10);
  Scene only_ball;
  only_ball.add_mesh(s.meshes()[1]);
  const uint32_t shift = s.mesh_base(1);
  const std::vector<Ray> rays = test::random_rays(12, 400);
  const std::vector<uint32_t> mask{0b10};
  for (const TraceMethod& m : test::backend_variants()) {
    SCOPED_TRACE(m.backend + "/" + m.variant);
    const auto b = build(m, s), ref = build(m, only_ball);
    std::vector<Hit> got(rays.size()), want(rays.size());
    b->intersect(rays, got, TraceOptions{.masks = mask, .filter = {}});
    ref->intersect(rays, want, Coherence::incoherent);
    size_t hits = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
      EXPECT_EQ(got[i].prim_id, want[i].hit() ? want[i].prim_id + shift : kInvalidId) << i;
      if (got[i].hit()) {
        EXPECT_EQ(s.geometry_of(got[i].prim_id), 1u);
      }
      hits += got[i].hit();
    }
    EXPECT_GT(hits, 30u);
    std::vector<uint8_t> occ(rays.size()), occ_want(rays.size());
    b->occluded(rays, occ, TraceOptions{.masks = mask, .filter = {}});
    ref->occluded(rays, occ_want, Coherence::incoherent);
    EXPECT_EQ(occ, occ_want);
    // A mask of 0 on a geometry hides it from the plain calls too (every ray's mask is ~0).
    Scene hidden = two_meshes();
    hidden.set_mask(0, 0);
    const auto h = build(m, hidden);
    h->intersect(rays, got, Coherence::coherent);
    for (size_t i = 0; i < rays.size(); ++i)
      EXPECT_EQ(got[i].prim_id, want[i].hit() ? want[i].prim_id + shift : kInvalidId) << i;
  }
}

TEST(Queries, AFilterCutsHolesAsAnAlphaMaskWould) {
  // Every third triangle rejected: the closest hit is the first accepted one of the reference's
  // every hit.
  const Scene s = two_meshes();
  const Reference reference(s);
  const std::vector<Ray> rays = test::random_rays(13, 400);
  TraceOptions o;
  o.filter = [](const HitCandidate& c) { return c.hit.prim_id % 3 != 0; };
  for (const TraceMethod& m : test::backend_variants()) {
    SCOPED_TRACE(m.backend + "/" + m.variant);
    const auto b = build(m, s);
    std::vector<Hit> got(rays.size());
    b->intersect(rays, got, o);
    std::vector<uint8_t> occ(rays.size());
    b->occluded(rays, occ, o);
    size_t off = 0, holes = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
      uint32_t want = kInvalidId;
      bool first_rejected = false;
      for (const ReferenceHit& h : reference.all_hits(rays[i]))
        if (h.prim_id % 3 != 0) {
          want = h.prim_id;
          break;
        } else if (want == kInvalidId) {
          first_rejected = true;
        }
      holes += first_rejected;
      off += got[i].prim_id != want;
      EXPECT_EQ(occ[i], uint8_t(got[i].hit())) << i;
      if (got[i].hit()) {
        EXPECT_NE(got[i].prim_id % 3, 0u);
      }
    }
    EXPECT_LE(off * 300, rays.size()) << off;
    EXPECT_GT(holes, 20u);
  }
}

TEST(Queries, GeometryIdsFollowTheOrderOfAdditionAndRemoval) {
  Scene s;
  const Scene soup = test::triangle_soup(1, 10);
  EXPECT_EQ(s.add_sphere({{0, 0, 0}, 1.0f, 0}), 0u);
  EXPECT_EQ(s.add_mesh(soup.meshes()[0]), 0u);  // mesh index 0, geometry 1
  EXPECT_EQ(s.mesh_geometry(0), 1u);
  EXPECT_EQ(s.add_plane({{0, 1, 0}, 2.0f, 0}), 2u);
  s.add_mesh(soup.meshes()[0]);
  EXPECT_EQ(s.geometry_count(), 4u);
  EXPECT_EQ(s.geometry_of(s.sphere_base()), 0u);
  EXPECT_EQ(s.geometry_of(0), 1u);
  EXPECT_EQ(s.geometry_of(s.mesh_base(1) + 3), 3u);
  EXPECT_EQ(s.geometry_of(s.plane_base()), 2u);
  s.set_mask(3, 7);
  s.remove_mesh(0);  // geometry 1 goes: the plane becomes 1, the second mesh 2
  EXPECT_EQ(s.geometry_count(), 3u);
  EXPECT_EQ(s.geometry_of(s.plane_base()), 1u);
  EXPECT_EQ(s.geometry_of(0), 2u);
  EXPECT_EQ(s.mask(2), 7u);
  EXPECT_EQ(s.geometry(2).kind, PrimKind::triangle);
  EXPECT_EQ(s.geometry(2).shape, 0u);
  EXPECT_EQ(test::error_of([&] { s.set_mask(3, 1); }), "set_mask: geometry 3 out of range (3 geometries)");
}

}  // namespace
}  // namespace rp
