// The double-precision reference (analysis/reference.h): closed-form answers, watertightness,
// exact agreement with a brute-force double loop, invalid rays, the tie rule, determinism.

#include "analysis/reference.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <random>
#include <vector>

#include "base/error.h"
#include "core/backend.h"
#include "core/geometry/plane.h"
#include "core/geometry/polygon.h"
#include "core/geometry/quadric.h"
#include "core/geometry/sphere.h"
#include "core/geometry/triangle.h"
#include "core/scene.h"
#include "core/scene_transform.h"
#include "tests/backends/oracle.h"
#include "tests/engine/reference_brute_force.h"
#include "tests/support/grid_scenes.h"
#include "tests/support/scenes.h"

namespace rp {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
using test::box_mesh;
using test::brute_force;
using test::grid_and_random_rays;
using test::mesh_of;
using test::quantized_uv_sphere;
using test::random_scene;
using test::signed_zero;
using test::uniform_vec;

/// hits equal the brute force bit for bit, and the independent oracle (tests/backends/oracle.h,
/// which shortens tfar as it goes and keeps no phantom filter) on prim_id, or on t when the
/// two pick different primitives of a tie, or the oracle's hit is a phantom.
void expect_matches_brute_force(const Scene& scene, const std::vector<Ray>& rays, const char* what,
                                double min_hit_fraction = 0.2) {
  const Reference ref(scene);
  std::vector<ReferenceHit> hits(rays.size());
  ref.intersect(rays, hits);
  int mismatches = 0, hits_seen = 0, oracle_ties = 0, oracle_phantoms = 0;
  for (size_t i = 0; i < rays.size() && mismatches < 10; ++i) {
    const ReferenceHit want = brute_force(scene, ref, rays[i]);
    const ReferenceHit& got = hits[i];
    hits_seen += got.hit();
    const bool same = got.prim_id == want.prim_id && got.instance_id == want.instance_id && got.t == want.t &&
                      got.u == want.u && got.v == want.v;
    if (!same) ++mismatches;
    EXPECT_TRUE(same) << what << " ray " << i << ": reference prim " << got.prim_id << " instance "
                      << got.instance_id << " t " << got.t << ", brute force prim " << want.prim_id << " instance "
                      << want.instance_id << " t " << want.t;
    const test::OracleHit o = test::oracle_intersect(scene, rays[i]);
    if (o.prim_id != got.prim_id || o.instance_id != got.instance_id) {
      if (o.hit() && !ref.plausible(rays[i], o.prim_id, o.t, o.instance_id)) {
        ++oracle_phantoms;
      } else {
        ++oracle_ties;
        EXPECT_EQ(o.t, got.t) << what << " ray " << i << ": oracle prim " << o.prim_id << ", reference prim "
                              << got.prim_id;
      }
    }
  }
  EXPECT_EQ(mismatches, 0) << what;
  EXPECT_GT(double(hits_seen), min_hit_fraction * double(rays.size())) << what << ": too few rays hit anything";
  EXPECT_LE(oracle_phantoms, int(rays.size() / 1000)) << what << ": phantoms should be rare";
  ::testing::Test::RecordProperty(std::string(what) + "_oracle_tie_picks", oracle_ties);
  ::testing::Test::RecordProperty(std::string(what) + "_oracle_phantoms", oracle_phantoms);
}

Ray ray(Vec3f org, Vec3f dir, float tnear = 0.0f, float tfar = kInf) { return {org, tnear, dir, tfar}; }

// ---- Closed-form answers --------------------------------------------------------------

TEST(ReferenceClosedForm, SphereAlongEachAxisHitsAtDistanceMinusRadius) {
  Scene s;
  const Vec3f c{1.5f, -2.25f, 3.0f};
  s.add_sphere({c, 0.75f, 0});
  const Reference ref(s);
  std::mt19937 rng(1);
  for (int axis = 0; axis < 3; ++axis)
    for (float sign : {-1.0f, 1.0f})
      for (float scale : {1.0f, 2.0f, 0.5f}) {
        Vec3f org = c, dir;
        org[axis] += sign * 10.0f;
        for (int k = 0; k < 3; ++k) dir[k] = signed_zero(rng);
        dir[axis] = -sign * scale;
        const ReferenceHit h = ref.intersect(ray(org, dir));
        ASSERT_TRUE(h.hit());
        EXPECT_EQ(h.prim_id, s.sphere_base());
        EXPECT_EQ(h.t, 9.25 / double(scale)) << "axis " << axis << " sign " << sign;
        // From inside, the far side: t = r / scale.
        const ReferenceHit in = ref.intersect(ray(c, dir));
        EXPECT_EQ(in.t, 0.75 / double(scale));
        // The interval ends are closed.
        EXPECT_TRUE(ref.intersect(ray(org, dir, 0.0f, float(9.25 / double(scale)))).hit());
        EXPECT_TRUE(ref.intersect(ray(org, dir, float(9.25 / double(scale)))).hit());
        EXPECT_EQ(ref.intersect(ray(org, dir, std::nextafter(float(9.25 / double(scale)), kInf))).t,
                  10.75 / double(scale));
        EXPECT_FALSE(ref.intersect(ray(org, dir, 0.0f, std::nextafter(float(9.25 / double(scale)), 0.0f))).hit());
      }
}

TEST(ReferenceClosedForm, SeedEllipsoidHitsAtTwoMinusSqrtFourFifths) {
  // Lecture notes "Ray-Surface Intersection", section 1 question 4:
  // (x-2)^2/4 + (y-2)^2 + z^2/4 = 1, r(t) = t (1, 1, 0).
  Scene s;
  s.add_quadric({Quadric<float>::ellipsoid({2.0f, 2.0f, 0.0f}, {2.0f, 1.0f, 2.0f}), 0});
  const Reference ref(s);
  const double root = std::sqrt(4.0 / 5.0);
  const ReferenceHit h = ref.intersect(ray({0, 0, 0}, {1, 1, 0}));
  ASSERT_TRUE(h.hit());
  EXPECT_EQ(h.prim_id, s.quadric_base());
  EXPECT_NEAR(h.t, 2.0 - root, 1e-14);
  const ReferenceHit h2 = ref.intersect(ray({0, 0, 0}, {1, 1, 0}, 2.0f));
  ASSERT_TRUE(h2.hit());
  EXPECT_NEAR(h2.t, 2.0 + root, 1e-14);
}

TEST(ReferenceClosedForm, PlaneHitsAtClosedFormTAndParallelOrBehindMisses) {
  Scene s;
  s.add_plane({{0.0f, 1.0f, 0.0f}, 2.0f, 0});  // y = -2
  const Reference ref(s);
  EXPECT_EQ(ref.intersect(ray({0.5f, 3.0f, -1.0f}, {0.0f, -1.0f, 0.0f})).t, 5.0);
  const ReferenceHit h = ref.intersect(ray({0.5f, 3.0f, -1.0f}, {0.3f, -2.0f, 0.1f}));
  EXPECT_EQ(h.t, 2.5);
  EXPECT_EQ(h.prim_id, s.plane_base());
  EXPECT_FALSE(ref.intersect(ray({0.5f, 3.0f, -1.0f}, {0.0f, 1.0f, 0.0f})).hit());
  EXPECT_FALSE(ref.intersect(ray({0.5f, 3.0f, -1.0f}, {1.0f, 0.0f, -0.0f})).hit());
  EXPECT_EQ(ref.node_count(), 0u);
}

TEST(ReferenceClosedForm, CylinderFromOutsideAndInside) {
  Scene s;
  s.add_quadric({Quadric<float>::cylinder({0, 0, 0}, 2, 2, 1), 0});  // radius 2 about y, |y| <= 1
  const Reference ref(s);
  EXPECT_NEAR(ref.intersect(ray({10.0f, 0.5f, 0.0f}, {-1.0f, 0.0f, -0.0f})).t, 8.0, 1e-13);
  EXPECT_NEAR(ref.intersect(ray({0.0f, 0.5f, -10.0f}, {-0.0f, 0.0f, 2.0f})).t, 4.0, 1e-13);
  EXPECT_NEAR(ref.intersect(ray({0.0f, 0.5f, 0.0f}, {1.0f, 0.0f, 0.0f})).t, 2.0, 1e-13);
  EXPECT_FALSE(ref.intersect(ray({10.0f, 1.5f, 0.0f}, {-1.0f, 0.0f, 0.0f})).hit());  // above the clip
  EXPECT_FALSE(ref.intersect(ray({0.0f, -5.0f, 0.0f}, {0.0f, 1.0f, 0.0f})).hit());   // along the open axis
}

// ---- Watertightness and robust traversal ----------------------------------------------

TEST(ReferenceWatertight, UnitSquareOfTwoTrianglesIsHitOnItsDiagonalAndBoundary) {
  Scene s;
  s.add_mesh(mesh_of({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, {0, 1, 2, 0, 2, 3}, "square"));
  const Reference ref(s);
  std::mt19937 rng(7);
  int checked = 0;
  for (int k = 0; k <= 64; ++k) {
    const float x = float(k) / 64.0f;
    // Straight down through (x, x, 0), with every sign of zero: both triangles at t = 1,
    // the larger prim_id wins the tie; through the boundary x = 0, y = x etc. from origins
    // on the box's faces (0 * inf would be NaN in a naive slab test).
    for (const Vec2f& p : {Vec2f{x, x}, Vec2f{0.0f, x}, Vec2f{1.0f, x}, Vec2f{x, 0.0f}, Vec2f{x, 1.0f}})
      for (int zeros = 0; zeros < 4; ++zeros) {
        const Ray r = ray({p.x, p.y, 1.0f}, {zeros & 1 ? -0.0f : 0.0f, zeros & 2 ? -0.0f : 0.0f, -1.0f});
        const ReferenceHit h = ref.intersect(r);
        ASSERT_TRUE(h.hit()) << "(" << p.x << ", " << p.y << ")";
        EXPECT_EQ(h.t, 1.0);
        EXPECT_EQ(h.prim_id, brute_force(s, ref, r).prim_id);
        ++checked;
      }
    // Oblique rays through exact diagonal points, from both sides.
    for (int n = 0; n < 8; ++n) {
      const Vec3f off{float(int(rng() % 33) - 16) / 16.0f, float(int(rng() % 33) - 16) / 16.0f,
                      n % 2 ? 1.0f : -1.0f};
      const Ray r = ray(Vec3f{x, x, 0.0f} + off, -off);
      const ReferenceHit h = ref.intersect(r);
      ASSERT_TRUE(h.hit()) << x;
      EXPECT_EQ(h.t, 1.0);
      ++checked;
    }
  }
  EXPECT_EQ(checked, 65 * (5 * 4 + 8));
}

TEST(ReferenceWatertight, ClosedMeshNeverLeaksThroughSharedEdgesOrVertices) {
  // Quantized vertices: every edge midpoint and every vertex is an exact float, and each ray
  // org = target + q, dir = -q (q on a 2^-6 grid) passes exactly through its target at t = 1
  // and then goes steeply inwards, so it must cross the closed surface.
  Scene s;
  s.add_mesh(quantized_uv_sphere(32, 16, {0.25f, -0.5f, 0.125f}, 1.0f));
  const MeshView& m = s.meshes()[0];
  const Reference ref(s);
  std::vector<Vec3f> targets(m.positions.begin(), m.positions.end());
  for (uint32_t t = 0; t < m.triangle_count(); ++t)
    for (int c = 0; c < 3; ++c) targets.push_back((m.vertex(t, c) + m.vertex(t, (c + 1) % 3)) * 0.5f);
  const Vec3f centre{0.25f, -0.5f, 0.125f};
  std::mt19937 rng(99);
  std::vector<Ray> rays;
  for (const Vec3f& target : targets) {
    const Vec3f radial = normalize(target - centre);
    rays.push_back(ray(centre + (target - centre) * 2.0f, centre - target));  // through the centre too
    for (int n = 0; n < 4; ++n) {
      Vec3f q;
      do {
        q = radial * 2.0f + uniform_vec(rng, -1.2f, 1.2f);
        for (int k = 0; k < 3; ++k) q[k] = std::round(q[k] * 64.0f) / 64.0f;
      } while (dot(normalize(q), radial) < 0.6f);
      rays.push_back(ray(target + q, -q));
    }
  }
  std::vector<ReferenceHit> hits(rays.size());
  ref.intersect(rays, hits);
  int leaks = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    leaks += !hits[i].hit();
    if (hits[i].hit()) {
      EXPECT_LE(hits[i].t, 1.0 + 1e-12) << "ray " << i << " hit beyond its target";
    }
    if (i % 16 == 0) {
      EXPECT_EQ(hits[i].prim_id, brute_force(s, ref, rays[i]).prim_id);
    }
  }
  EXPECT_EQ(leaks, 0) << "of " << rays.size() << " rays through edge midpoints and vertices";
}

TEST(ReferenceTraversal, AxisParallelRaysWithSignedZerosAlongBoxFacesEdgesAndVertices) {
  // A closed box whose faces lie on BVH box faces; rays with origins on the grid (on the
  // faces, edges and corners), +-0 in the other components, grazing along faces and edges.
  Scene s;
  s.add_mesh(box_mesh({-0.5f, -0.25f, 0.0f}, {0.5f, 0.75f, 1.0f}));
  s.add_mesh(box_mesh({0.5f, -0.25f, 0.0f}, {1.0f, 0.25f, 0.5f}));  // shares a face plane
  std::vector<Ray> rays;
  for (int axis = 0; axis < 3; ++axis)
    for (float sign : {-1.0f, 1.0f})
      for (int a = -6; a <= 6; ++a)
        for (int b = -6; b <= 6; ++b)
          for (int zeros = 0; zeros < 4; ++zeros)
            for (float start : {-3.0f, 0.0f, 0.5f}) {
              Ray r;
              r.org[axis] = start == -3.0f ? -3.0f * sign : start;
              r.org[(axis + 1) % 3] = 0.25f * float(a);
              r.org[(axis + 2) % 3] = 0.25f * float(b);
              r.dir[axis] = sign;
              r.dir[(axis + 1) % 3] = zeros & 1 ? -0.0f : 0.0f;
              r.dir[(axis + 2) % 3] = zeros & 2 ? -0.0f : 0.0f;
              rays.push_back(r);
            }
  expect_matches_brute_force(s, rays, "axis_parallel_boxes", 0.1);
}

TEST(ReferenceWatertight, PhantomHitOfARayLyingInATrianglesPlaneIsDropped) {
  // Found by the agreement sweep: the ray lies exactly in the triangle's plane (n . dir == 0
  // and n . (org - v0) == 0 in exact arithmetic) and passes beside it, yet the watertight
  // test's determinant is rounding noise and it may report a "hit" far from the triangle.
  const Vec3f v0{0.25f, 1.0f, -1.0f}, v1{0.0f, 1.25f, -0.5f}, v2{0.5f, 0.25f, -1.0f};
  const Ray r = ray({-1.0f, 1.0f, 2.75f}, {2.25f, -3.75f, -3.0f});
  const Vec3d n = triangle_normal(Vec3d(v0), Vec3d(v1), Vec3d(v2));
  ASSERT_EQ(dot(n, Vec3d(r.dir)), 0.0);
  ASSERT_EQ(dot(n, Vec3d(r.org) - Vec3d(v0)), 0.0);
  // A second triangle that the ray does hit, at t = 1 in the plane y = -2.75, shares the
  // phantom's leaf: traversal visits the phantom, and the plausibility test must drop it.
  Scene s;
  s.add_mesh(mesh_of({v0, v1, v2, {-5.0f, -2.75f, -5.0f}, {5.0f, -2.75f, -5.0f}, {0.0f, -2.75f, 5.0f}},
                     {0, 1, 2, 3, 4, 5}, "tris"));
  const Reference ref(s);
  const Rayd rd{Vec3d(r.org), double(r.tnear), Vec3d(r.dir), double(r.tfar)};
  const Intersection<double> h = intersect_triangle_watertight(rd, Vec3d(v0), Vec3d(v1), Vec3d(v2));
  if (h.hit) {
    EXPECT_FALSE(Box3d(Vec3d(min(min(v0, v1), v2)), Vec3d(max(max(v0, v1), v2))).contains(rd.at(h.t)));
    EXPECT_FALSE(ref.plausible(r, 0, h.t));
  }
  const ReferenceHit got = ref.intersect(r);
  EXPECT_EQ(got.prim_id, 1u);
  EXPECT_EQ(got.t, 1.0);
  // A genuine hit of the same triangle is plausible.
  const Ray down = ray({0.25f, 0.75f, 3.0f}, {0.0f, 0.0f, -1.0f});
  const ReferenceHit g = ref.intersect(down);
  ASSERT_TRUE(g.hit());
  EXPECT_TRUE(ref.plausible(down, 0, g.t));
  EXPECT_FALSE(ref.plausible(down, 1, g.t));  // no such primitive
}

// ---- Agreement with brute force -------------------------------------------------------

TEST(ReferenceAgreement, EqualsBruteForceBitForBitOnRandomScenes) {
  for (uint32_t seed : {1u, 2u, 3u}) {
    const Scene s = random_scene(seed, 300, {0, 0, 0});
    expect_matches_brute_force(s, grid_and_random_rays(seed + 100, 3000, {0, 0, 0}), "random_scene");
  }
}

TEST(ReferenceAgreement, EqualsBruteForceFarFromTheOrigin) {
  const Vec3f offset{1024.0f, -512.0f, 2048.0f};
  const Scene s = random_scene(11, 300, offset);
  expect_matches_brute_force(s, grid_and_random_rays(111, 3000, offset), "offset_scene");
}

TEST(ReferenceAgreement, EqualsBruteForceOnADeepBvhBuiltInParallel) {
  // More primitives than the parallel build threshold, so subtrees are built as TBB tasks.
  Scene s = random_scene(21, 12000, {0, 0, 0});
  s.add_mesh(quantized_uv_sphere(64, 32, {-1.0f, 0.5f, 0.25f}, 1.25f));
  EXPECT_GT(s.prim_count(), 16000u);
  expect_matches_brute_force(s, grid_and_random_rays(121, 600, {0, 0, 0}), "deep_bvh");
}

TEST(ReferenceAgreement, EqualsBruteForceWithInstances) {
  // Instanced meshes placed several times (rotated, scaled unevenly, mirrored) beside world
  // geometry, then the same scene moved far from the origin: the instances' transforms compose.
  const Scene s = test::instanced_scene();
  expect_matches_brute_force(s, grid_and_random_rays(131, 3000, {0, 0, 0}), "instances");
  const Vec3f offset{1024.0f, -512.0f, 2048.0f};
  expect_matches_brute_force(transformed(s, 1.0, Vec3d(offset)), grid_and_random_rays(132, 3000, offset),
                             "instances_offset");
}

TEST(ReferenceAgreement, InstancesGiveTheHitsOfTheirTrianglesBakedIntoTheWorld) {
  // The same triangles flattened into world meshes (mapped in double, rounded to float): the
  // same hit or miss and t within 1e-5 relative, wherever the oracle is well-conditioned.
  const Scene s = test::instanced_scene(), flat = test::flattened(s);
  const Reference a(s), b(flat);
  const std::vector<Ray> rays = grid_and_random_rays(133, 4000, {0, 0, 0});
  int instance_hits = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    const ReferenceHit ha = a.intersect(rays[i]), hb = b.intersect(rays[i]);
    instance_hits += ha.instance_id != kNoInstance;
    if (ha.hit() == hb.hit() && (!ha.hit() || std::abs(ha.t - hb.t) <= 1e-5 * hb.t)) continue;
    if (test::oracle_ambiguous(s, rays[i], 1e-4f) || test::oracle_ambiguous(flat, rays[i], 1e-4f)) continue;
    ADD_FAILURE() << "ray " << i << ": instanced prim " << ha.prim_id << " instance " << ha.instance_id << " t "
                  << ha.t << ", flattened prim " << hb.prim_id << " t " << hb.t;
  }
  EXPECT_GT(instance_hits, 150);  // of 4000 rays, about 200 hit an instance
}

// ---- Rules: invalid rays, empty scenes, ties, determinism -----------------------------

TEST(ReferenceRules, InvalidRaysMiss) {
  const Scene s = random_scene(5, 50, {0, 0, 0});
  const Reference ref(s);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const Ray good = ray({0.0f, 0.0f, 5.0f}, {0.0f, 0.0f, -1.0f});
  ASSERT_TRUE(ref.intersect(good).hit());
  std::vector<Ray> bad;
  for (int k = 0; k < 3; ++k) {
    for (float x : {nan, kInf, -kInf}) {
      Ray r = good;
      r.org[k] = x;
      bad.push_back(r);
      r = good;
      r.dir[k] = x;
      bad.push_back(r);
    }
  }
  Ray r = good;
  r.dir = {0.0f, -0.0f, 0.0f};
  bad.push_back(r);
  r = good;
  r.tnear = -1.0f;
  bad.push_back(r);
  r = good;
  r.tnear = 3.0f;
  r.tfar = 2.0f;
  bad.push_back(r);
  r = good;
  r.tfar = nan;
  bad.push_back(r);
  r = good;
  r.tnear = nan;
  bad.push_back(r);
  std::vector<ReferenceHit> hits(bad.size(), ReferenceHit{1.0, 7, 0.5, 0.5});
  ref.intersect(bad, hits);
  for (size_t i = 0; i < bad.size(); ++i) {
    const ReferenceHit h = ref.intersect(bad[i]);
    EXPECT_FALSE(h.hit()) << "ray " << i;
    EXPECT_EQ(h.t, std::numeric_limits<double>::infinity());
    EXPECT_EQ(h.u, 0.0);
    EXPECT_EQ(h.v, 0.0);
    EXPECT_FALSE(hits[i].hit()) << "batch ray " << i;
  }
}

TEST(ReferenceRules, EmptySceneMissesAndPlanesAloneNeedNoBvh) {
  const Scene empty;
  const Reference ref(empty);
  EXPECT_EQ(ref.node_count(), 0u);
  EXPECT_EQ(ref.bytes(), 0u);
  EXPECT_GE(ref.build_seconds(), 0.0);
  const std::vector<Ray> rays = grid_and_random_rays(3, 300, {0, 0, 0});
  std::vector<ReferenceHit> hits(rays.size());
  ref.intersect(rays, hits);
  for (size_t i = 0; i < rays.size(); ++i) {
    EXPECT_FALSE(ref.intersect(rays[i]).hit());
    EXPECT_FALSE(hits[i].hit());
  }
  std::vector<ReferenceHit> none;
  ref.intersect(std::span<const Ray>(), none);
  EXPECT_THROW(ref.intersect(rays, none), Error);
}

TEST(ReferenceRules, AtEqualTTheLargerPrimIdWins) {
  Scene s;
  const std::vector<Vec3f> tri{{-1, -1, 0}, {2, -1, 0}, {-1, 2, 0}};
  s.add_mesh(mesh_of(tri, {0, 1, 2}, "a"));
  s.add_mesh(mesh_of(tri, {0, 1, 2}, "b"));  // the same triangle again: prim 1
  s.add_polygon(std::vector<Vec3f>{{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}}, 0);
  const Reference only_tris = [&] {
    Scene t;
    t.add_mesh(mesh_of(tri, {0, 1, 2}, "a"));
    t.add_mesh(mesh_of(tri, {0, 1, 2}, "b"));
    return Reference(t);
  }();
  const Ray down = ray({0.25f, 0.125f, 3.0f}, {0.0f, 0.0f, -1.0f});
  EXPECT_EQ(only_tris.intersect(down).prim_id, 1u);
  EXPECT_EQ(only_tris.intersect(down).t, 3.0);
  const Reference ref(s);
  EXPECT_EQ(ref.intersect(down).prim_id, s.polygon_base());  // triangle, triangle, polygon all at t = 3
  Scene with_plane = s;
  with_plane.add_plane({{0, 0, 1}, 0.0f, 0});  // z = 0: a plane takes a tie, as in Scene::intersect_planes
  const Reference refp(with_plane);
  EXPECT_EQ(refp.intersect(down).prim_id, with_plane.plane_base());
  EXPECT_EQ(refp.intersect(down).t, 3.0);
  EXPECT_EQ(refp.intersect(down).prim_id, brute_force(with_plane, refp, down).prim_id);
}

TEST(ReferenceRules, BatchEqualsSingleRaysAndIsTheSameForAnyThreadCount) {
  Scene s = random_scene(31, 9000, {0, 0, 0});  // over the parallel build threshold
  const std::vector<Ray> rays = grid_and_random_rays(131, 5000, {0, 0, 0});
  std::vector<ReferenceHit> one(rays.size()), two(rays.size());
  size_t bytes_one = 0, nodes_one = 0;
  {
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    const Reference ref(s);
    ref.intersect(rays, one);
    bytes_one = ref.bytes();
    nodes_one = ref.node_count();
  }
  const Reference ref(s);
  ref.intersect(rays, two);
  EXPECT_EQ(ref.bytes(), bytes_one);
  EXPECT_EQ(ref.node_count(), nodes_one);
  EXPECT_EQ(ref.node_count() % 2, 1u);  // binary tree: 2 * leaves - 1
  EXPECT_GT(ref.bytes(), size_t(s.prim_count()) * 40);
  for (size_t i = 0; i < rays.size(); ++i) {
    const ReferenceHit single = ref.intersect(rays[i]);
    ASSERT_EQ(one[i].prim_id, two[i].prim_id) << i;
    ASSERT_EQ(one[i].t, two[i].t) << i;
    ASSERT_EQ(single.prim_id, two[i].prim_id) << i;
    ASSERT_EQ(single.t, two[i].t) << i;
    ASSERT_EQ(single.u, two[i].u) << i;
    ASSERT_EQ(single.v, two[i].v) << i;
  }
}

TEST(ReferenceRules, OutlivesTheSceneItWasBuiltFrom) {
  std::vector<Ray> rays = grid_and_random_rays(41, 500, {0, 0, 0});
  std::vector<ReferenceHit> want(rays.size());
  std::unique_ptr<const Reference> ref;
  {
    const Scene s = random_scene(41, 100, {0, 0, 0});
    ref = std::make_unique<const Reference>(s);
    for (size_t i = 0; i < rays.size(); ++i) want[i] = brute_force(s, *ref, rays[i]);
  }
  for (size_t i = 0; i < rays.size(); ++i) EXPECT_EQ(ref->intersect(rays[i]).prim_id, want[i].prim_id);
}

}  // namespace
}  // namespace rp
