// Scene model: one flat primitive numbering, validation messages, surface data, default scene.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <random>

#include "base/error.h"
#include "core/scene.h"
#include "tests/support/error_of.h"
#include "tests/support/scenes.h"

namespace rp {
namespace {

TriangleMesh two_triangles(const std::string& name) {
  TriangleMesh m;
  m.name = name;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  m.indices = {0, 1, 2, 1, 3, 2};
  return m;
}

TEST(SceneNumbering, MeshesThenSpheresQuadricsPolygonsPlanes) {
  Scene s;
  s.add_plane({{0, 1, 0}, 0, 0});
  s.add_mesh(two_triangles("a"));
  s.add_sphere({{0, 0, 0}, 1, 0});
  s.add_mesh(two_triangles("b"));
  s.add_quadric({Quadric<float>::ellipsoid({0, 0, 0}, {1, 2, 3}), 0});
  const std::vector<Vec3f> tri{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  s.add_polygon(tri, 0);
  ASSERT_EQ(s.prim_count(), 4u + 1 + 1 + 1 + 1);
  const PrimKind kinds[] = {PrimKind::triangle, PrimKind::triangle, PrimKind::triangle, PrimKind::triangle,
                            PrimKind::sphere,   PrimKind::quadric,  PrimKind::polygon,  PrimKind::plane};
  const uint32_t shapes[] = {0, 0, 1, 1, 0, 0, 0, 0};
  const uint32_t locals[] = {0, 1, 0, 1, 0, 0, 0, 0};
  for (uint32_t id = 0; id < s.prim_count(); ++id) {
    const PrimLocation r = s.locate(id);
    EXPECT_EQ(r.kind, kinds[id]) << id;
    EXPECT_EQ(r.shape, shapes[id]) << id;
    EXPECT_EQ(r.local, locals[id]) << id;
  }
  EXPECT_EQ(s.mesh_base(1), 2u);
  EXPECT_EQ(s.sphere_base(), 4u);
  EXPECT_EQ(s.plane_base(), 7u);
}

void expect_error(const std::function<void()>& f, const std::string& message) {
  EXPECT_EQ(test::error_of(f), message);
}

TEST(SceneValidation, BadMeshesAreRejectedWithTheReason) {
  Scene s;
  TriangleMesh m = two_triangles("bad");
  m.indices[4] = 9;
  expect_error([&] { s.add_mesh(m); }, "mesh 'bad': triangle 1 uses vertex 9 of 4");
  m = two_triangles("nan");
  m.positions[2].y = std::numeric_limits<float>::quiet_NaN();
  expect_error([&] { s.add_mesh(m); }, "mesh 'nan': vertex 2 has a non-finite coordinate");
  m = two_triangles("short");
  m.indices.pop_back();
  expect_error([&] { s.add_mesh(m); }, "mesh 'short': index count 5 is not a multiple of 3");
  m = two_triangles("mat");
  m.material = 3;
  expect_error([&] { s.add_mesh(m); }, "mesh 'mat': material index 3 out of range (1 materials)");
  expect_error([&] { s.add_sphere({{0, 0, 0}, -1, 0}); },
               "sphere at (0, 0, 0) radius -1: needs a finite centre and radius > 0");
  const std::vector<Vec3f> line{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  expect_error([&] { s.add_polygon(line, 0); }, "polygon: vertices are collinear (zero area)");
  EXPECT_EQ(s.prim_count(), 0u);
}

TEST(SceneValidation, GeometryOutsideTheCoordinateRangeIsRefused) {
  // core/ray.h: every scene coordinate within 2^30; one float past it is refused.
  const float edge = kMaxCoordinate, past = std::nextafter(kMaxCoordinate, 2 * kMaxCoordinate);
  const std::string range = " is outside the supported coordinate range |x| <= 1073741824 (2^30)";
  Scene s;
  TriangleMesh m = two_triangles("far");
  m.positions[3] = {1, edge, -edge};
  s.add_mesh(m);  // at the edge: fine
  m.positions[3] = {1, past, 0};
  expect_error([&] { s.add_mesh(m); }, "mesh 'far': vertex 3 (1, 1.07374e+09, 0)" + range);
  s.add_sphere({{0, edge - 256, 0}, 256, 0});  // floats are 64 apart below 2^30, 128 above
  expect_error([&] { s.add_sphere({{0, edge - 128, 0}, 256, 0}); },
               "sphere at (0, 1.07374e+09, 0) radius 256: its box" + range);
  const std::vector<Vec3f> far_polygon{{0, 0, 0}, {past, 0, 0}, {0, 1, 0}};
  expect_error([&] { s.add_polygon(far_polygon, 0); }, "polygon: vertex (1.07374e+09, 0, 0)" + range);
  expect_error([&] { s.add_plane({{0, 2, 0}, -2 * past, 0}); },
               "plane: its distance from the origin, 1.07374e+09, is outside the supported coordinate range |x| <= "
               "1073741824 (2^30)");
  s.add_plane({{0, 2, 0}, -2 * edge, 0});
  Quadricf q;
  q.A = q.B = q.C = 1;
  q.J = -1;
  q.clip = {{-1, -1, -1}, {past, 1, 1}};
  expect_error([&] { s.add_quadric({q, 0}); },
               "quadric: clipping box (-1, -1, -1) - (1.07374e+09, 1, 1) or centre (0, 0, 0)" + range);
  expect_error([&] { s.add_light(PointLight{{0, 0, -1e19f}, Vec3f(1.0f)}); }, "point light at (0, 0, -1e+19): outside "
                                                                             "the supported coordinate range |x| <= "
                                                                             "1073741824 (2^30)");
  expect_error([&] { s.add_light(DirectionalLight{{0, 0, 0}, Vec3f(1.0f)}); },
               "directional light: direction (0, 0, 0) must be finite and non-zero");
  EXPECT_EQ(s.prim_count(), 2u + 1 + 1);  // the two triangles, the sphere and the plane at the edge
}

TEST(SceneValidation, QuadricsAreStoredWithPowerOfTwoNormalizedCoefficients) {
  Scene s;
  const Quadricf small = Quadricf::ellipsoid({5, 0, 0}, {1e-3f, 2e-3f, 3e-3f});  // A = 1e6
  s.add_quadric({small, 0});
  const Quadricf& q = s.quadrics()[0].quadric;
  const float scale = q.A / small.A;
  EXPECT_EQ(scale, std::exp2(std::round(std::log2(scale)))) << "a power of two";
  for (auto [stored, given] : {std::pair{q.A, small.A}, std::pair{q.B, small.B}, std::pair{q.C, small.C},
                                std::pair{q.J, small.J}})
    EXPECT_EQ(stored, given * scale);
  EXPECT_GE(std::max({std::abs(q.A), std::abs(q.B), std::abs(q.C), std::abs(q.J)}), 1.0f);
  EXPECT_LT(std::max({std::abs(q.A), std::abs(q.B), std::abs(q.C), std::abs(q.J)}), 2.0f);
  // The same surface: the same hits, bit for bit.
  const Ray r{{5, 0, -0.01f}, 0, {0, 0, 1}, 10};
  const Intersection<float> a = intersect_quadric(r, small), b = s.intersect_analytic(s.quadric_base(), r);
  ASSERT_TRUE(a.hit);
  EXPECT_EQ(a.t, b.t);
}

TEST(SceneSurface, TrianglePointAndNormalFromBarycentrics) {
  Scene s;
  TriangleMesh m = two_triangles("t");
  m.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
  s.add_mesh(m);
  const Ray r{{0.25f, 0.5f, 1.0f}, 0.0f, {0, 0, -1}, 10.0f};
  const SurfacePoint sp = s.surface(r, Hit{1.0f, 0, 0.25f, 0.5f});
  EXPECT_EQ(sp.position, (Vec3f{0.25f, 0.5f, 0.0f}));
  EXPECT_EQ(sp.geometric_normal, (Vec3f{0, 0, 1}));
  EXPECT_EQ(sp.shading_normal, (Vec3f{0, 0, 1}));
}

TEST(SceneSurface, SpherePointLiesOnTheSphere) {
  Scene s;
  s.add_sphere({{1, 2, 3}, 2, 0});
  const Ray r{{1, 2, 10}, 0, {0, 0, -1}, 100};
  const SurfacePoint sp = s.surface(r, Hit{5.0f, 0, 0, 0});
  EXPECT_FLOAT_EQ(length(sp.position - Vec3f{1, 2, 3}), 2.0f);
  EXPECT_EQ(sp.geometric_normal, (Vec3f{0, 0, 1}));
}

TEST(SceneInstances, AMeshIsStoredOnceAndCountedOncePerPlacement) {
  Scene s;
  s.add_mesh(two_triangles("world"));
  const uint32_t m = s.add_instanced_mesh(two_triangles("placed"));
  Affine3f shift;
  for (int k = 0; k < 3; ++k) {
    shift.m[0][3] = 10.0f * float(k + 1);
    EXPECT_EQ(s.add_instance(m, shift), uint32_t(k));
  }
  EXPECT_EQ(s.triangle_count(), 4u);  // each mesh's triangles once in the numbering
  EXPECT_EQ(s.instanced_triangle_count(), 6u);
  EXPECT_TRUE(s.is_instanced(m));
  EXPECT_FALSE(s.is_instanced(0));
  EXPECT_EQ(s.mesh_base(m), 2u);
  // The world's bounds: the world mesh and the instances' boxes, not the placed mesh itself.
  EXPECT_EQ(s.bounds().lo, Vec3f(0.0f, 0.0f, 0.0f));
  EXPECT_EQ(s.bounds().hi, Vec3f(31.0f, 1.0f, 0.0f));
  EXPECT_EQ(s.instances()[1].bounds.lo, Vec3f(20.0f, 0.0f, 0.0f));
}

TEST(SceneInstances, BadPlacementsAreRejectedWithTheReason) {
  Scene s;
  const uint32_t world = s.add_mesh(two_triangles("w"));
  const uint32_t m = s.add_instanced_mesh(two_triangles("p"));
  expect_error([&] { s.add_instance(world, {}); }, "instance 0: mesh 'w' is a world mesh, not an instanced one");
  expect_error([&] { s.add_instance(7, {}); }, "instance 0: mesh 7 out of range (2 meshes)");
  Affine3f flat;
  flat.m[2][2] = 0.0f;
  expect_error([&] { s.add_instance(m, flat); }, "instance 0: the transform of mesh 'p' is not invertible");
  Affine3f nan;
  nan.m[1][3] = std::numeric_limits<float>::quiet_NaN();
  expect_error([&] { s.add_instance(m, nan); }, "instance 0: the transform of mesh 'p' is not finite");
  Affine3f tiny;
  tiny.m[0][0] = tiny.m[1][1] = tiny.m[2][2] = 0x1p-21f;
  expect_error([&] { s.add_instance(m, tiny); },
               "instance 0: the transform of mesh 'p' stretches by 2.09715e+06, beyond 1.04858e+06 (2^20) either way");
  Affine3f far;
  far.m[0][3] = 0x1p30f;
  expect_error([&] { s.add_instance(m, far); },
               "instance 0: mesh 'p' placed at (1.07374e+09, 0, 0) - (1.07374e+09, 1, 0) is outside the supported "
               "coordinate range |x| <= 1073741824 (2^30)");
  EXPECT_TRUE(s.instances().empty());
}

TEST(SceneInstances, SurfaceIsTheObjectSpacePointMappedWithNormalsByTheInverseTranspose) {
  // A unit right triangle in z = 0, scaled by (2, 3, -1) (a mirror) and moved by (1, 2, 3):
  // the hit at (u, v) = (0.25, 0.5) is at (1 + 2 * 0.25, 2 + 3 * 0.5, 3), and the geometric
  // normal points where the baked triangle's would: (c1 - c0) x (c2 - c0) = (2,0,0) x (0,3,0).
  Scene s;
  TriangleMesh m;
  m.name = "t";
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.indices = {0, 1, 2};
  const uint32_t mesh = s.add_instanced_mesh(m);
  Affine3f a;
  a.m[0][0] = 2.0f;
  a.m[1][1] = 3.0f;
  a.m[2][2] = -1.0f;
  a.m[0][3] = 1.0f;
  a.m[1][3] = 2.0f;
  a.m[2][3] = 3.0f;
  s.add_instance(mesh, a);
  EXPECT_EQ(s.instances()[0].orientation, -1.0f);
  const Ray r{{1.5f, 3.5f, 10.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, std::numeric_limits<float>::infinity()};
  const SurfacePoint sp = s.surface(r, Hit{7.0f, 0, 0.25f, 0.5f, 0});
  EXPECT_FLOAT_EQ(sp.position.x, 1.5f);
  EXPECT_FLOAT_EQ(sp.position.y, 3.5f);
  EXPECT_FLOAT_EQ(sp.position.z, 3.0f);
  EXPECT_EQ(sp.geometric_normal, Vec3f(0.0f, 0.0f, 1.0f));
  EXPECT_EQ(sp.shading_normal, Vec3f(0.0f, 0.0f, 1.0f));
}

TEST(SceneInstances, TheFloatInverseIsTheInverseToAFewUlpsAndRefusesSingularMaps) {
  // Against the double inverse of the same float map (an independent computation): random
  // rotations, uneven scales and far translations, each entry within a few float ulps of the
  // map's size; the float inverse composed with the map is the identity as closely.
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int k = 0; k < 1000; ++k) {
    const Affine3f a = test::placement({0.2f + std::abs(u(rng)) * 3.0f, 0.2f + std::abs(u(rng)), -0.5f + u(rng) * 0.2f},
                                       {u(rng), u(rng), 1.0f}, 180.0f * u(rng), {100 * u(rng), 100 * u(rng), 100 * u(rng)});
    const std::optional<Affine3f> f = float_inverse(a);
    const std::optional<Affine3d> d = inverse(Affine3d(a));
    ASSERT_TRUE(f && d);
    const double size = std::max({Affine3d(*f).linear_norm(), 1.0});
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 4; ++j)
        EXPECT_NEAR(f->m[i][j], d->m[i][j], (j == 3 ? 200.0 : 1.0) * size * 8e-7) << k << " [" << i << "][" << j << "]";
    const Affine3d id = compose(Affine3d(*f), Affine3d(a));
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 4; ++j) EXPECT_NEAR(id.m[i][j], i == j ? 1.0 : 0.0, j == 3 ? 2e-4 : 2e-6) << k;
  }
  Affine3f flat;
  flat.m[2][2] = 0.0f;
  EXPECT_FALSE(float_inverse(flat).has_value());
  Affine3f tiny;
  for (int i = 0; i < 3; ++i) tiny.m[i][i] = 1e-20f;  // det 1e-60 underflows to 0 in float
  EXPECT_FALSE(float_inverse(tiny).has_value());
}

TEST(DefaultScene, HasEveryPrimitiveKindAndAFiftyThousandTriangleMesh) {
  const Scene s = make_default_scene();
  EXPECT_GE(s.triangle_count(), 50000u);
  EXPECT_GE(s.spheres().size(), 1u);
  EXPECT_GE(s.quadrics().size(), 1u);
  EXPECT_GE(s.polygons().size(), 1u);
  EXPECT_GE(s.planes().size(), 1u);
  EXPECT_FALSE(s.point_lights().empty() && s.directional_lights().empty());
  EXPECT_TRUE(s.camera().has_value());
  EXPECT_EQ(s.degenerate_triangle_count(), 0u);
  const Box3f b = s.bounds();
  EXPECT_FALSE(b.empty());
  EXPECT_TRUE(is_finite(b.lo) && is_finite(b.hi));
}

}  // namespace
}  // namespace rp

namespace rp {
namespace {

TEST(SceneInstances, TheLargestStretchBoundsEveryVectorsStretchAndIsReached) {
  // Against the largest stretch seen over many directions (a lower bound that approaches it)
  // and the scale of a pure scaling, on placements of every kind: uniform, uneven, mirrored,
  // sheared.
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<Affine3f> maps = {test::placement({2, 2, 2}, {0, 1, 0}, 30, {1, 2, 3}),
                                test::placement({0.5f, 3, 0.25f}, {1, 1, 0}, 70, {0, 0, 0}),
                                test::placement({-1, 1, 1}, {0, 0, 1}, 10, {0, 0, 0})};
  Affine3f shear;
  shear.m[0][1] = 4.0f;
  maps.push_back(shear);
  for (const Affine3f& m : maps) {
    const double bound = m.largest_stretch();
    double seen = 0;
    for (int k = 0; k < 20000; ++k) {
      const Vec3d v = normalize(Vec3d(n(rng), n(rng), n(rng)));
      seen = std::max(seen, length(Affine3d(m).vector(v)));
    }
    EXPECT_GE(bound, seen);
    EXPECT_LE(bound, seen * 1.001);
  }
  EXPECT_NEAR(test::placement({0.5f, 3, 0.25f}, {0, 1, 0}, 0, {0, 0, 0}).largest_stretch(), 3.0f, 1e-5f);
}

}  // namespace
}  // namespace rp
