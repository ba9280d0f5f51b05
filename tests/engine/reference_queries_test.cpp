// The double reference's queries beyond the closest hit (analysis/reference.h): every hit along
// a ray, counts and closest points, against brute force in double (reference_brute_force.h)
// bit for bit on scenes of every primitive kind, world and instanced; closed-form answers; the
// interval, radius, tie and invalid-input rules; the quadric refusal; batches and threads.

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "analysis/reference.h"
#include "base/error.h"
#include "core/geometry/sphere.h"
#include "core/queries.h"
#include "core/scene.h"
#include "core/scene_transform.h"
#include "tests/engine/reference_brute_force.h"
#include "tests/support/error_of.h"
#include "tests/support/grid_scenes.h"
#include "tests/support/scenes.h"

namespace rp {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

Ray ray(Vec3f org, Vec3f dir, float tnear = 0.0f, float tfar = kInf) { return {org, tnear, dir, tfar}; }

bool same(const ReferenceHit& a, const ReferenceHit& b) {
  return a.t == b.t && a.prim_id == b.prim_id && a.instance_id == b.instance_id && a.u == b.u && a.v == b.v;
}

bool same(const ReferencePoint& a, const ReferencePoint& b) {
  return a.point == b.point && a.distance == b.distance && a.prim_id == b.prim_id && a.instance_id == b.instance_id &&
         a.u == b.u && a.v == b.v;
}

/// The kinds of primitive an answer came from: bit k for PrimKind k, bit 7 for an instance's
/// triangle.
uint32_t kind_bit(const Scene& s, uint32_t prim_id, uint32_t instance_id) {
  if (instance_id != kNoInstance) return 1u << 7;
  return 1u << uint32_t(s.locate(prim_id).kind);
}

// ---- Every hit ---------------------------------------------------------------------------

/// all_hits (batched and single) equals brute force bit for bit, count_hits its sizes, and
/// intersect the last of a ray's hits at its smallest t; the scene must show second roots,
/// and the kinds in `kinds_wanted` (kind_bit) among the hits.
void expect_hits_match_brute_force(const Scene& s, const std::vector<Ray>& rays, const char* what,
                                   uint32_t kinds_wanted) {
  const Reference ref(s);
  const ReferenceHitList list = ref.all_hits(rays);
  std::vector<uint32_t> counts(rays.size());
  ref.count_hits(rays, counts);
  ASSERT_EQ(list.offsets.size(), rays.size() + 1) << what;
  int mismatches = 0;
  size_t hits = 0, second_roots = 0;
  uint32_t kinds = 0;
  for (size_t i = 0; i < rays.size() && mismatches < 10; ++i) {
    const std::vector<ReferenceHit> want = test::brute_force_hits(s, ref, rays[i]);
    const std::span<const ReferenceHit> got = list.of(i);
    bool equal = got.size() == want.size();
    for (size_t k = 0; equal && k < got.size(); ++k) equal = same(got[k], want[k]);
    const std::vector<ReferenceHit> single = ref.all_hits(rays[i]);
    equal =
        equal && single.size() == got.size() &&
        std::equal(single.begin(), single.end(), got.begin(), [](const auto& a, const auto& b) { return same(a, b); });
    mismatches += !equal;
    EXPECT_TRUE(equal) << what << " ray " << i << ": " << got.size() << " hits, brute force " << want.size();
    EXPECT_EQ(counts[i], got.size()) << what << " ray " << i;
    // The closest hit is the last of the hits at the smallest t.
    EXPECT_TRUE(same(ref.intersect(rays[i]), test::brute_force(s, ref, rays[i]))) << what << " ray " << i;
    hits += got.size();
    for (size_t k = 0; k < got.size(); ++k) {
      kinds |= kind_bit(s, got[k].prim_id, got[k].instance_id);
      for (size_t j = 0; j < k; ++j)
        second_roots += got[j].prim_id == got[k].prim_id && got[j].instance_id == got[k].instance_id;
    }
  }
  EXPECT_EQ(mismatches, 0) << what;
  EXPECT_GT(2 * hits, rays.size()) << what << ": too few hits";
  EXPECT_GT(second_roots, 10u) << what << ": too few primitives crossed twice";
  EXPECT_EQ(kinds & kinds_wanted, kinds_wanted) << what << ": kinds hit " << kinds;
}

constexpr uint32_t kEveryKind = (1u << uint32_t(PrimKind::triangle)) | (1u << uint32_t(PrimKind::sphere)) |
                                (1u << uint32_t(PrimKind::quadric)) | (1u << uint32_t(PrimKind::polygon)) |
                                (1u << uint32_t(PrimKind::plane));
constexpr uint32_t kInstanced = 1u << 7;

TEST(ReferenceAllHits, EqualBruteForceBitForBitOnRandomScenes) {
  for (uint32_t seed : {1u, 2u, 3u}) {
    const Scene s = test::random_scene(seed, 300, {0, 0, 0});
    expect_hits_match_brute_force(s, test::grid_and_random_rays(seed + 200, 2000, {0, 0, 0}), "random_scene",
                                  kEveryKind);
  }
  const Vec3f offset{1024.0f, -512.0f, 2048.0f};
  expect_hits_match_brute_force(test::random_scene(11, 300, offset), test::grid_and_random_rays(211, 2000, offset),
                                "offset_scene", kEveryKind);
}

TEST(ReferenceAllHits, EqualBruteForceBitForBitWithInstances) {
  const Scene s = test::instanced_scene_with_polygon();
  expect_hits_match_brute_force(s, test::grid_and_random_rays(231, 3000, {0, 0, 0}), "instances",
                                kEveryKind | kInstanced);
  const Vec3f offset{1024.0f, -512.0f, 2048.0f};
  expect_hits_match_brute_force(transformed(s, 1.0, Vec3d(offset)), test::grid_and_random_rays(232, 3000, offset),
                                "instances_offset", kEveryKind | kInstanced);
}

TEST(ReferenceAllHits, ASphereIsCrossedTwiceATangentOnceAndBothEndsAreClosed) {
  Scene s;
  const Vec3f c{1.5f, -2.25f, 3.0f};
  s.add_sphere({c, 0.75f, 0});
  const Reference ref(s);
  for (int axis = 0; axis < 3; ++axis)
    for (float sign : {-1.0f, 1.0f})
      for (float scale : {1.0f, 2.0f, 0.5f}) {
        Vec3f org = c, dir{0.0f};
        org[axis] += sign * 10.0f;
        dir[axis] = -sign * scale;
        const double t0 = 9.25 / double(scale), t1 = 10.75 / double(scale);
        const std::vector<ReferenceHit> both = ref.all_hits(ray(org, dir));
        ASSERT_EQ(both.size(), 2u) << "axis " << axis;
        EXPECT_EQ(both[0].t, t0);
        EXPECT_EQ(both[1].t, t1);
        EXPECT_EQ(both[0].prim_id, s.sphere_base());
        EXPECT_EQ(both[1].prim_id, s.sphere_base());
        EXPECT_EQ(ref.all_hits(ray(c, dir)).size(), 1u);  // from the centre: the far side
        const std::vector<ReferenceHit> first = ref.all_hits(ray(org, dir, 0.0f, float(t0)));
        ASSERT_EQ(first.size(), 1u);
        EXPECT_EQ(first[0].t, t0);
        const std::vector<ReferenceHit> second = ref.all_hits(ray(org, dir, float(t1)));
        ASSERT_EQ(second.size(), 1u);
        EXPECT_EQ(second[0].t, t1);
        EXPECT_TRUE(
            ref.all_hits(ray(org, dir, std::nextafter(float(t0), kInf), std::nextafter(float(t1), 0.0f))).empty());
      }
  // Tangent: a double root at t = 5, listed once.
  Scene unit;
  unit.add_sphere({{0.0f, 0.0f, 0.0f}, 1.0f, 0});
  const Reference tangent(unit);
  const std::vector<ReferenceHit> once = tangent.all_hits(ray({-5.0f, 1.0f, 0.0f}, {1.0f, 0.0f, 0.0f}));
  ASSERT_EQ(once.size(), 1u);
  EXPECT_EQ(once[0].t, 5.0);
}

TEST(ReferenceAllHits, QuadricsPlanesDuplicatesAndInstancesAreEachListed) {
  Scene s;
  s.add_quadric({Quadric<float>::cylinder({20, 0, 0}, 2, 2, 1), 0});  // radius 2 about x = 20, z = 0, |y| <= 1
  const std::vector<Vec3f> tri{{-1, -1, 5}, {2, -1, 5}, {-1, 2, 5}};
  s.add_mesh(test::mesh_of(tri, {0, 1, 2}, "a"));
  s.add_mesh(test::mesh_of(tri, {0, 1, 2}, "b"));  // the same triangle again
  s.add_plane({{0.0f, 0.0f, 1.0f}, -7.0f, 0});     // z = 7
  const uint32_t m = s.add_instanced_mesh(test::mesh_of({{-1, -1, 0}, {2, -1, 0}, {-1, 2, 0}}, {0, 1, 2}, "c"));
  const Affine3f up = test::placement({1, 1, 1}, {0, 0, 1}, 0.0f, {0.0f, 0.0f, 6.0f});
  s.add_instance(m, up);
  s.add_instance(m, up);  // placed twice at the same place
  const Reference ref(s);
  // Through the cylinder's axis: two crossings.
  const std::vector<ReferenceHit> cyl = ref.all_hits(ray({30.0f, 0.5f, 0.0f}, {-1.0f, 0.0f, -0.0f}));
  ASSERT_EQ(cyl.size(), 2u);
  EXPECT_NEAR(cyl[0].t, 8.0, 1e-13);
  EXPECT_NEAR(cyl[1].t, 12.0, 1e-13);
  // Up through the triangles, the instances and the plane: t 5, 5, 6, 6, 7, by (t, prim, instance).
  const Ray upward = ray({0.25f, 0.125f, 0.0f}, {0.0f, 0.0f, 1.0f});
  const std::vector<ReferenceHit> h = ref.all_hits(upward);
  ASSERT_EQ(h.size(), 5u);
  const uint32_t c0 = s.mesh_base(m);
  const ReferenceHit want[5] = {{5.0, 0, 0, 0, kNoInstance},
                                {5.0, 1, 0, 0, kNoInstance},
                                {6.0, c0, 0, 0, 0},
                                {6.0, c0, 0, 0, 1},
                                {7.0, s.plane_base(), 0, 0, kNoInstance}};
  for (int k = 0; k < 5; ++k) {
    EXPECT_EQ(h[size_t(k)].t, want[k].t) << k;
    EXPECT_EQ(h[size_t(k)].prim_id, want[k].prim_id) << k;
    EXPECT_EQ(h[size_t(k)].instance_id, want[k].instance_id) << k;
  }
  EXPECT_EQ(ref.intersect(upward).prim_id, 1u);  // the closest hit: the larger id at t = 5
  std::vector<uint32_t> n(1);
  ref.count_hits(std::span<const Ray>(&upward, 1), n);
  EXPECT_EQ(n[0], 5u);
}

TEST(ReferenceAllHits, InvalidRaysHaveNoHits) {
  const Scene s = test::random_scene(5, 50, {0, 0, 0});
  const Reference ref(s);
  const Ray good = ray({0.0f, 0.0f, 5.0f}, {0.0f, 0.0f, -1.0f});
  ASSERT_FALSE(ref.all_hits(good).empty());
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<Ray> bad(6, good);
  bad[0].org.x = nan;
  bad[1].dir.y = kInf;
  bad[2].dir = {0.0f, -0.0f, 0.0f};
  bad[3].tnear = -1.0f;
  bad[4].tnear = 3.0f;
  bad[4].tfar = 2.0f;
  bad[5].tfar = nan;
  std::vector<uint32_t> counts(bad.size(), 7);
  ref.count_hits(bad, counts);
  const ReferenceHitList list = ref.all_hits(bad);
  for (size_t i = 0; i < bad.size(); ++i) {
    EXPECT_TRUE(ref.all_hits(bad[i]).empty()) << i;
    EXPECT_EQ(counts[i], 0u) << i;
    EXPECT_EQ(list.count(i), 0u) << i;
  }
}

TEST(ReferenceAllHits, BatchesAreTheSameForAnyThreadCountAndMaxPerRayKeepsTheNearest) {
  const Scene s = test::random_scene(31, 9000, {0, 0, 0});  // over the parallel build threshold
  const std::vector<Ray> rays = test::grid_and_random_rays(331, 3000, {0, 0, 0});
  ReferenceHitList one;
  {
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = Reference(s).all_hits(rays);
  }
  const Reference ref(s);
  const ReferenceHitList all = ref.all_hits(rays), two = ref.all_hits(rays, 2);
  ASSERT_EQ(one.offsets, all.offsets);
  size_t cut = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    for (size_t k = 0; k < all.count(i); ++k) ASSERT_TRUE(same(one.of(i)[k], all.of(i)[k])) << i;
    ASSERT_EQ(two.count(i), std::min<size_t>(2, all.count(i))) << i;
    for (size_t k = 0; k < two.count(i); ++k) EXPECT_TRUE(same(two.of(i)[k], all.of(i)[k])) << i;
    cut += all.count(i) > 2;
  }
  EXPECT_GT(cut, 100u);
  EXPECT_TRUE(ref.all_hits(std::span<const Ray>()).hits.empty());
  std::vector<uint32_t> counts(rays.size() - 1);
  EXPECT_EQ(test::error_of([&] { ref.count_hits(rays, counts); }), "Reference::count_hits: 3000 rays but 2999 counts");
}

// ---- Closest points ----------------------------------------------------------------------

/// Query points around a scene (at `offset`): random in [-3.5, 3.5]^3, points of the 0.25 grid
/// (on the grid scenes' faces, edges and vertices: distance 0 and exact ties between
/// duplicates), vertices of world meshes, polygons and placed instances (rounded to float); a
/// third of them with a radius in [0, 1].
std::vector<PointQuery> query_points(const Scene& s, uint32_t seed, int count, Vec3f offset) {
  std::mt19937 rng(seed);
  std::vector<Vec3f> vertices;
  for (size_t m = 0; m < s.meshes().size(); ++m)
    if (!s.is_instanced(m))
      vertices.insert(vertices.end(), s.meshes()[m].positions.begin(), s.meshes()[m].positions.end());
  vertices.insert(vertices.end(), s.polygon_vertices().begin(), s.polygon_vertices().end());
  for (const Instance& in : s.instances())
    for (const Vec3f& p : s.meshes()[in.mesh].positions)
      vertices.push_back(Vec3f(Affine3d(in.object_to_world).point(Vec3d(p))));
  std::vector<PointQuery> out;
  for (int n = 0; n < count; ++n) {
    PointQuery q;
    if (n % 3 == 0) q.point = offset + test::uniform_vec(rng, -3.5f, 3.5f);
    if (n % 3 == 1) q.point = offset + test::grid_vec(rng);
    if (n % 3 == 2) q.point = vertices[rng() % vertices.size()];
    if (rng() % 3 == 0) q.radius = test::uniform(rng, 0.0f, 1.0f);
    out.push_back(q);
  }
  return out;
}

/// closest_points (batched and single) equals brute force bit for bit; the answers must come
/// from the kinds in `kinds_wanted` (kind_bit), some at distance 0, some cut by the radius.
void expect_points_match_brute_force(const Scene& s, const std::vector<PointQuery>& queries, const char* what,
                                     uint32_t kinds_wanted) {
  const Reference ref(s);
  std::vector<ReferencePoint> got(queries.size());
  ref.closest_points(queries, got);
  int mismatches = 0;
  size_t on_surface = 0, cut_by_radius = 0;
  uint32_t kinds = 0;
  for (size_t i = 0; i < queries.size() && mismatches < 10; ++i) {
    const ReferencePoint want = test::brute_force_point(s, queries[i]);
    const bool equal = same(got[i], want) && same(ref.closest_point(queries[i]), want);
    mismatches += !equal;
    EXPECT_TRUE(equal) << what << " point " << i << ": reference prim " << got[i].prim_id << " instance "
                       << got[i].instance_id << " distance " << got[i].distance << ", brute force prim " << want.prim_id
                       << " instance " << want.instance_id << " distance " << want.distance;
    if (got[i].found()) kinds |= kind_bit(s, got[i].prim_id, got[i].instance_id);
    on_surface += got[i].distance == 0.0;
    cut_by_radius += !got[i].found() && test::brute_force_point(s, {queries[i].point}).found();
  }
  EXPECT_EQ(mismatches, 0) << what;
  EXPECT_EQ(kinds & kinds_wanted, kinds_wanted) << what << ": kinds found " << kinds;
  EXPECT_GT(on_surface, 0u) << what;
  EXPECT_GT(cut_by_radius, 0u) << what;
}

constexpr uint32_t kPointKinds = (1u << uint32_t(PrimKind::triangle)) | (1u << uint32_t(PrimKind::sphere)) |
                                 (1u << uint32_t(PrimKind::polygon)) | (1u << uint32_t(PrimKind::plane));

TEST(ReferenceClosestPoint, EqualsBruteForceBitForBitOnRandomScenes) {
  for (uint32_t seed : {1u, 2u, 3u}) {
    const Scene s = test::without_quadrics(test::random_scene(seed, 300, {0, 0, 0}));
    expect_points_match_brute_force(s, query_points(s, seed + 300, 1500, {0, 0, 0}), "random_scene", kPointKinds);
  }
  const Vec3f offset{1024.0f, -512.0f, 2048.0f};
  const Scene far = test::without_quadrics(test::random_scene(11, 300, offset));
  expect_points_match_brute_force(far, query_points(far, 311, 1500, offset), "offset_scene", kPointKinds);
  // A deep tree built in parallel.
  const Scene deep = test::without_quadrics(test::random_scene(21, 12000, {0, 0, 0}));
  expect_points_match_brute_force(deep, query_points(deep, 321, 300, {0, 0, 0}), "deep_bvh",
                                  1u << uint32_t(PrimKind::triangle));
}

TEST(ReferenceClosestPoint, EqualsBruteForceBitForBitWithInstances) {
  // Instances rotated, scaled unevenly and mirrored; then the scene far from the origin.
  const Scene s = test::without_quadrics(test::instanced_scene_with_polygon());
  expect_points_match_brute_force(s, query_points(s, 331, 2000, {0, 0, 0}), "instances", kPointKinds | kInstanced);
  const Vec3f offset{1024.0f, -512.0f, 2048.0f};
  const Scene far = transformed(s, 1.0, Vec3d(offset));
  expect_points_match_brute_force(far, query_points(far, 332, 2000, offset), "instances_offset",
                                  kPointKinds | kInstanced);
}

TEST(ReferenceClosestPoint, ClosedFormPointsOfSpheresTrianglesPolygonsPlanesAndInstances) {
  Scene s;
  s.add_mesh(test::mesh_of({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {0, 1, 2}, "tri"));
  const Vec3f c{5.0f, 2.0f, 3.0f};
  s.add_sphere({c, 0.5f, 0});
  s.add_polygon(std::vector<Vec3f>{{-6, -1, -6}, {-4, -1, -6}, {-4, 1, -6}, {-6, 1, -6}}, 0);  // z = -6
  s.add_plane({{0.0f, 1.0f, 0.0f}, -20.0f, 0});                                                // y = 20
  // The triangle again, doubled and moved to z = 10 by an instance.
  const uint32_t m = s.add_instanced_mesh(test::mesh_of({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {0, 1, 2}, "placed"));
  s.add_instance(m, test::placement({2, 2, 2}, {0, 0, 1}, 0.0f, {0.0f, 0.0f, 10.0f}));
  const Reference ref(s);
  const auto at = [&](Vec3f p, float radius = kInf) { return ref.closest_point({p, radius}); };

  const ReferencePoint face = at({0.25f, 0.25f, 1.0f});  // above the face
  EXPECT_EQ(face.prim_id, 0u);
  EXPECT_EQ(face.point, Vec3d(0.25, 0.25, 0.0));
  EXPECT_EQ(face.distance, 1.0);
  EXPECT_EQ(face.u, 0.25);
  EXPECT_EQ(face.v, 0.25);
  const ReferencePoint corner = at({2.0f, -1.0f, 0.0f});  // beyond vertex (1, 0, 0)
  EXPECT_EQ(corner.point, Vec3d(1.0, 0.0, 0.0));
  EXPECT_EQ(corner.distance, std::sqrt(2.0));
  EXPECT_EQ(corner.u, 1.0);
  EXPECT_EQ(corner.v, 0.0);

  const ReferencePoint ball = at(c + Vec3f{0.0f, 0.0f, 2.0f});
  EXPECT_EQ(ball.prim_id, s.sphere_base());
  EXPECT_EQ(ball.point, Vec3d(c) + Vec3d(0.0, 0.0, 0.5));
  EXPECT_EQ(ball.distance, 1.5);
  const Vec2<double> uv = sphere_uv(Vec3d(c), 0.5, ball.point);
  EXPECT_EQ(ball.u, uv.x);
  EXPECT_EQ(ball.v, uv.y);
  const ReferencePoint centre = at(c);  // every point is as close: the one on +x
  EXPECT_EQ(centre.point, Vec3d(c) + Vec3d(0.5, 0.0, 0.0));
  EXPECT_EQ(centre.distance, 0.5);

  const ReferencePoint square = at({-5.0f, 0.5f, -3.0f});
  EXPECT_EQ(square.prim_id, s.polygon_base());
  EXPECT_EQ(square.point, Vec3d(-5.0, 0.5, -6.0));
  EXPECT_EQ(square.distance, 3.0);

  const ReferencePoint plane = at({0.5f, 17.0f, 0.25f});
  EXPECT_EQ(plane.prim_id, s.plane_base());
  EXPECT_EQ(plane.point, Vec3d(0.5, 20.0, 0.25));
  EXPECT_EQ(plane.distance, 3.0);

  // The instance's triangle is (0,0,10), (2,0,10), (0,2,10) in the world: the world distance,
  // the barycentrics of the mesh's own triangle.
  const ReferencePoint placed = at({0.5f, 1.0f, 13.0f});
  EXPECT_EQ(placed.prim_id, s.mesh_base(m));
  EXPECT_EQ(placed.instance_id, 0u);
  EXPECT_EQ(placed.point, Vec3d(0.5, 1.0, 10.0));
  EXPECT_EQ(placed.distance, 3.0);
  EXPECT_EQ(placed.u, 0.25);
  EXPECT_EQ(placed.v, 0.5);
}

TEST(ReferenceClosestPoint, TheRadiusIsClosedAndInvalidQueriesFindNothing) {
  Scene s;
  s.add_plane({{0.0f, 0.0f, 1.0f}, 0.0f, 0});  // z = 0
  s.add_sphere({{0.0f, 0.0f, -5.0f}, 1.0f, 0});
  const Reference ref(s);
  EXPECT_EQ(ref.closest_point({{0.0f, 0.0f, 0.5f}, 0.5f}).distance, 0.5);
  EXPECT_FALSE(ref.closest_point({{0.0f, 0.0f, 0.5f}, std::nextafter(0.5f, 0.0f)}).found());
  EXPECT_EQ(ref.closest_point({{0.25f, 1.0f, 0.0f}, 0.0f}).distance, 0.0);  // on the plane, radius 0
  EXPECT_EQ(ref.closest_point({{0.0f, 0.0f, -3.5f}, 1.0f}).prim_id, s.sphere_base());
  EXPECT_FALSE(ref.closest_point({{0.0f, 0.0f, -2.0f}, 1.0f}).found());  // both at 2
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::vector<PointQuery> bad{{{nan, 0.0f, 0.0f}},
                                    {{0.0f, kInf, 0.0f}},
                                    {{0.0f, 0.0f, -kInf}},
                                    {{0.0f, 0.0f, 1.0f}, -1.0f},
                                    {{0.0f, 0.0f, 1.0f}, nan}};
  std::vector<ReferencePoint> out(bad.size(), ReferencePoint{Vec3d(1.0), 1.0, 3, 0, 0.5, 0.5});
  ref.closest_points(bad, out);
  for (size_t i = 0; i < bad.size(); ++i)
    for (const ReferencePoint& p : {out[i], ref.closest_point(bad[i])}) {
      EXPECT_FALSE(p.found()) << i;
      EXPECT_TRUE(same(p, ReferencePoint{})) << i;
    }
  std::vector<ReferencePoint> short_out(1);
  EXPECT_EQ(test::error_of([&] { ref.closest_points(bad, short_out); }),
            "Reference::closest_points: 5 queries but 1 answers");
}

TEST(ReferenceClosestPoint, AtEqualDistanceTheLowestPrimIdThenInstanceWins) {
  Scene s;
  const std::vector<Vec3f> tri{{-1, -1, 0}, {2, -1, 0}, {-1, 2, 0}};
  s.add_plane({{0.0f, 0.0f, 1.0f}, 0.0f, 0});  // z = 0 too, the largest prim_id
  s.add_mesh(test::mesh_of(tri, {0, 1, 2}, "a"));
  s.add_mesh(test::mesh_of(tri, {0, 1, 2}, "b"));
  const uint32_t m = s.add_instanced_mesh(test::mesh_of(tri, {0, 1, 2}, "c"));
  const Affine3f down = test::placement({1, 1, 1}, {0, 0, 1}, 0.0f, {0.0f, 0.0f, -2.0f});
  s.add_instance(m, down);
  s.add_instance(m, down);
  const Reference ref(s);
  const ReferencePoint above = ref.closest_point({{0.25f, 0.125f, 3.0f}});
  EXPECT_EQ(above.prim_id, 0u);  // triangles 0, 1 and the plane, all at 3
  EXPECT_EQ(above.distance, 3.0);
  EXPECT_EQ(ref.intersect(ray({0.25f, 0.125f, 3.0f}, {0.0f, 0.0f, -1.0f})).prim_id, s.plane_base());  // rays: largest
  const ReferencePoint below = ref.closest_point({{0.25f, 0.125f, -2.5f}});
  EXPECT_EQ(below.prim_id, s.mesh_base(m));  // both instances at 0.5
  EXPECT_EQ(below.instance_id, 0u);
  EXPECT_EQ(below.distance, 0.5);
}

TEST(ReferenceClosestPoint, QuadricsAreRefusedAsTheBackendsRefuseThem) {
  Scene s = test::instanced_scene();
  const std::vector<PointQuery> q{{{0.0f, 0.0f, 0.0f}}};
  std::vector<ReferencePoint> out(1);
  {
    const Reference ref(s);
    const std::string one =
        "reference: closest points: the scene has 1 quadric (quadrics have no closest-point routine)";
    EXPECT_EQ(test::error_of([&] { ref.closest_point(q[0]); }), one);
    EXPECT_EQ(test::error_of([&] { ref.closest_points(q, out); }), one);
  }
  s.add_quadric({Quadric<float>::ellipsoid({3.0f, 0.0f, 0.0f}, {0.5f, 0.3f, 0.4f}), 0});
  EXPECT_EQ(test::error_of([&] { Reference(s).closest_point(q[0]); }),
            "reference: closest points: the scene has 2 quadrics (quadrics have no closest-point routine)");
  EXPECT_TRUE(Reference(test::without_quadrics(s)).closest_point(q[0]).found());
}

TEST(ReferenceClosestPoint, BatchesAreTheSameForAnyThreadCount) {
  const Scene s = test::without_quadrics(test::random_scene(31, 9000, {0, 0, 0}));
  const std::vector<PointQuery> q = query_points(s, 341, 2000, {0, 0, 0});
  std::vector<ReferencePoint> one(q.size()), two(q.size());
  {
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    Reference(s).closest_points(q, one);
  }
  Reference(s).closest_points(q, two);
  for (size_t i = 0; i < q.size(); ++i) ASSERT_TRUE(same(one[i], two[i])) << i;
}

}  // namespace
}  // namespace rp
