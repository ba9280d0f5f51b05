/// The JSON scene loader: docs/example-scene.json loads as written (counts, camera, materials,
/// the mesh transform), defaults and mesh materials, and the exact message of every error.
/// Small files are written to a scratch folder by the tests themselves.

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "base/error.h"
#include "base/text.h"
#include "io/loaders/load.h"
#include "io/ordered_json.h"
#include "scratch.h"
#include "tests/support/build_paths.h"

namespace rp {
namespace {

namespace fs = std::filesystem;

const std::string kExample = std::string(test::kSourceDir) + "/docs/example-scene.json";

using test::scratch;
using test::write_file;

/// what() of the rp::Error that `f` throws with the scratch folder's path removed, or "no error".
std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    std::string s = e.what();
    const std::string dir = scratch().string() + "/";
    for (size_t at = s.find(dir); at != std::string::npos; at = s.find(dir)) s.erase(at, dir.size());
    return s;
  }
  return "no error";
}

Scene json_scene(const std::string& text, const std::string& name = "scene.json") {
  return load_scene(write_file(name, text));
}

std::string json_error(const std::string& text, const std::string& name = "scene.json") {
  const std::string path = write_file(name, text);
  return error_of([&] { load_scene(path); });
}

/// `{"objects": [<object>]}`, the smallest scene around one object.
std::string with_object(const std::string& object) { return R"({"objects": [)" + object + "]}"; }

void expect_near(const Vec3f& a, const Vec3f& b, float tolerance, const char* what) {
  EXPECT_LE(length(Vec3d(a) - Vec3d(b)), tolerance)
      << what << ": (" << a.x << ", " << a.y << ", " << a.z << ") vs (" << b.x << ", " << b.y << ", " << b.z << ")";
}

/// a as the scene stores it (coefficients normalized) against b as constructed.
void expect_same_quadric(const Quadricf& a, const Quadricf& constructed) {
  const Quadricf b = constructed.normalized();
  EXPECT_EQ(a.A, b.A);
  EXPECT_EQ(a.B, b.B);
  EXPECT_EQ(a.C, b.C);
  EXPECT_EQ(a.D, b.D);
  EXPECT_EQ(a.E, b.E);
  EXPECT_EQ(a.F, b.F);
  EXPECT_EQ(a.G, b.G);
  EXPECT_EQ(a.H, b.H);
  EXPECT_EQ(a.I, b.I);
  EXPECT_EQ(a.J, b.J);
  EXPECT_EQ(a.center, b.center);
  EXPECT_EQ(a.clip, b.clip);
}

uint32_t material_id(const Scene& s, const std::string& name) {
  for (uint32_t i = 0; i < s.materials().size(); ++i)
    if (s.materials()[i].name == name) return i;
  ADD_FAILURE() << "no material " << name;
  return 0;
}

// --- The example -------------------------------------------------------------------------------

TEST(JsonSceneExample, LoadsEveryKindOfObjectLightAndTheCamera) {
  const Scene s = load_scene(kExample);
  ASSERT_EQ(s.meshes().size(), 1u);
  EXPECT_EQ(s.meshes()[0].triangle_count(), 8u);
  EXPECT_EQ(s.meshes()[0].positions.size(), 24u);  // flat normals: 3 corners per face
  EXPECT_EQ(s.spheres().size(), 1u);
  EXPECT_EQ(s.quadrics().size(), 7u);
  ASSERT_EQ(s.polygons().size(), 1u);
  EXPECT_EQ(s.polygons()[0].count, 10u);
  EXPECT_FALSE(s.polygons()[0].convex);
  EXPECT_EQ(s.planes().size(), 1u);
  EXPECT_EQ(s.prim_count(), 8u + 1u + 7u + 1u + 1u);
  EXPECT_EQ(s.materials().size(), 8u);  // the default grey and 7 of the file

  ASSERT_EQ(s.point_lights().size(), 1u);
  EXPECT_EQ(s.point_lights()[0].position, Vec3f(4, 8, 6));
  EXPECT_EQ(s.point_lights()[0].intensity, Vec3f(90, 88, 80));
  ASSERT_EQ(s.directional_lights().size(), 1u);
  expect_near(s.directional_lights()[0].direction, Vec3f(normalize(Vec3d(-0.4, -1, -0.5))), 1e-7f, "light");
  EXPECT_EQ(s.directional_lights()[0].irradiance, Vec3f(0.3f, 0.3f, 0.35f));

  ASSERT_TRUE(s.camera().has_value());
  EXPECT_EQ(s.camera()->eye, Vec3f(0, 4.5f, 12));
  EXPECT_EQ(s.camera()->look_at, Vec3f(0, 1, -0.5f));
  EXPECT_EQ(s.camera()->up, Vec3f(0, 1, 0));
  EXPECT_EQ(s.camera()->vfov_degrees, 45.0f);
}

TEST(JsonSceneExample, MaterialsTakeIdsInFileOrderAndObjectsRefertoThemByName) {
  const Scene s = load_scene(kExample);
  const std::vector<std::string> names = {"default", "floor", "red", "chrome", "glass", "gold", "blue", "lamp"};
  ASSERT_EQ(s.materials().size(), names.size());
  for (size_t i = 0; i < names.size(); ++i) EXPECT_EQ(s.materials()[i].name, names[i]);

  const Material& red = s.materials()[material_id(s, "red")];
  EXPECT_EQ(red.diffuse, Vec3f(0.8f, 0.12f, 0.1f));
  EXPECT_EQ(red.specular, Vec3f(0.4f));
  EXPECT_EQ(red.shininess, 60.0f);
  EXPECT_EQ(red.emission, Vec3f(0.0f));
  EXPECT_EQ(red.mirror, 0.0f);
  EXPECT_EQ(red.ior, 1.0f);
  EXPECT_EQ(red.opacity, 1.0f);
  const Material& glass = s.materials()[material_id(s, "glass")];
  EXPECT_EQ(glass.ior, 1.5f);
  EXPECT_EQ(glass.opacity, 0.25f);
  EXPECT_EQ(glass.emission, Vec3f(0.0f));  // a default
  EXPECT_EQ(s.materials()[material_id(s, "chrome")].mirror, 0.85f);
  EXPECT_EQ(s.materials()[material_id(s, "lamp")].emission, Vec3f(0.9f, 0.75f, 0.4f));
  EXPECT_EQ(s.materials()[material_id(s, "lamp")].shininess, 32.0f);  // a default

  EXPECT_EQ(s.planes()[0].material, material_id(s, "floor"));
  EXPECT_EQ(s.polygons()[0].material, material_id(s, "gold"));
  EXPECT_EQ(s.spheres()[0].material, material_id(s, "chrome"));
  EXPECT_EQ(s.meshes()[0].material, material_id(s, "glass"));
  EXPECT_TRUE(s.meshes()[0].face_materials.empty());
  const std::vector<std::string> quadric_materials = {"red", "blue", "gold", "red", "lamp", "blue", "gold"};
  for (size_t i = 0; i < quadric_materials.size(); ++i)
    EXPECT_EQ(s.quadrics()[i].material, material_id(s, quadric_materials[i])) << "quadric " << i;
}

TEST(JsonSceneExample, QuadricsAreTheNamedConstructorsAndTheGeneralForm) {
  const Scene s = load_scene(kExample);
  ASSERT_EQ(s.quadrics().size(), 7u);
  expect_same_quadric(s.quadrics()[0].quadric, Quadricf::ellipsoid({-5, 1, -2}, {0.8f, 1, 0.6f}));
  expect_same_quadric(s.quadrics()[1].quadric, Quadricf::cylinder({-2.5f, 0.6f, -2}, 0.6f, 0.6f, 0.9f, 2));
  expect_same_quadric(s.quadrics()[2].quadric, Quadricf::cone({0, 1, -2}, 0.5f, 0.5f, 1, 1));
  expect_same_quadric(s.quadrics()[3].quadric,
                      Quadricf::hyperboloid_one_sheet({2.5f, 1, -2}, 0.35f, 0.35f, 0.5f, 1, 1));
  expect_same_quadric(s.quadrics()[4].quadric, Quadricf::hyperboloid_two_sheets({5, 1, -2}, 0.4f, 0.4f, 0.3f, 1, 0));
  expect_same_quadric(s.quadrics()[5].quadric, Quadricf::paraboloid({-1.5f, 0.05f, 1.5f}, 0.8f, 0.8f, 1.2f, 1));
  Quadricf saddle;
  saddle.F = 1;
  saddle.H = -1;
  saddle.center = {4.2f, 1, 1.5f};
  saddle.clip = {{3.4f, 0.3f, 0.7f}, {5, 1.7f, 2.3f}};
  expect_same_quadric(s.quadrics()[6].quadric, saddle);

  EXPECT_EQ(s.spheres()[0].center, Vec3f(-4, 1, 1.5f));
  EXPECT_EQ(s.spheres()[0].radius, 1.0f);
  EXPECT_EQ(s.planes()[0].normal, Vec3f(0, 1, 0));
  EXPECT_EQ(s.planes()[0].d, 0.0f);
  EXPECT_EQ(s.polygon_vertices()[0], Vec3f(0, 4.4f, -4));
  EXPECT_EQ(s.polygon_vertices()[2], Vec3f(-1.141f, 3.571f, -4));
}

TEST(JsonSceneExample, MeshIsScaledThenRotatedThenTranslatedNormalsByTheInverseTranspose) {
  const Scene s = load_scene(kExample);
  const TriangleMesh m = to_triangle_mesh(s.meshes()[0]);
  // scale (0.8, 1.2, 0.8), 30 degrees about +y (x -> (cos, 0, -sin)), translate (1.5, 1.2, 1.5).
  const double c = std::cos(kPi / 6), sn = std::sin(kPi / 6);
  auto expected = [&](double x, double y, double z) {
    x *= 0.8, y *= 1.2, z *= 0.8;
    return Vec3f(Vec3d(c * x + sn * z + 1.5, y + 1.2, -sn * x + c * z + 1.5));
  };
  // The file's vertex 1 = (1, 0, 0) lands at (1.5 + 0.8 cos 30, 1.2, 1.5 - 0.8 sin 30).
  const Vec3f tip = expected(1, 0, 0);
  expect_near(tip, Vec3f(2.19282032f, 1.2f, 1.1f), 1e-6f, "tip");
  EXPECT_TRUE(std::any_of(m.positions.begin(), m.positions.end(),
                          [&](const Vec3f& p) { return length(Vec3d(p) - Vec3d(tip)) < 1e-6; }));
  const std::vector<Vec3f> corners = {expected(1, 0, 0),  expected(-1, 0, 0), expected(0, 1, 0),
                                      expected(0, -1, 0), expected(0, 0, 1),  expected(0, 0, -1)};
  for (const Vec3f& p : m.positions)
    EXPECT_TRUE(
        std::any_of(corners.begin(), corners.end(), [&](const Vec3f& q) { return length(Vec3d(p) - Vec3d(q)) < 1e-6; }))
        << p.x << " " << p.y << " " << p.z;
  // The lowest corner rests on the floor.
  expect_near(expected(0, -1, 0), Vec3f(1.5f, 0, 1.5f), 1e-6f, "bottom");

  // Flat normals stay perpendicular to their transformed faces only under the inverse transpose.
  ASSERT_EQ(m.normals.size(), m.positions.size());
  for (uint32_t t = 0; t < m.triangle_count(); ++t) {
    const Vec3d face =
        normalize(cross(Vec3d(m.vertex(t, 1)) - Vec3d(m.vertex(t, 0)), Vec3d(m.vertex(t, 2)) - Vec3d(m.vertex(t, 0))));
    for (int k = 0; k < 3; ++k) {
      const Vec3d n(m.normals[m.indices[3 * t + k]]);
      EXPECT_NEAR(length(n), 1.0, 1e-6);
      EXPECT_GT(dot(n, face), 1.0 - 1e-6) << "triangle " << t;
    }
  }
}

// --- Defaults, lights and meshes ---------------------------------------------------------------

TEST(JsonScene, OmittedKeysTakeTheirDocumentedDefaults) {
  const Scene s = json_scene(R"json({"camera": {}, "materials": {"plain": {}}, "objects": [
      {"type": "sphere"}, {"type": "plane"}, {"type": "quadric", "shape": "cylinder"},
      {"type": "quadric", "shape": "hyperboloid2", "c": 0.5}, {"type": "quadric", "shape": "ellipsoid"}]})json");
  EXPECT_EQ(s.camera()->eye, CameraDesc{}.eye);
  EXPECT_EQ(s.camera()->look_at, CameraDesc{}.look_at);
  EXPECT_EQ(s.camera()->up, CameraDesc{}.up);
  EXPECT_EQ(s.camera()->vfov_degrees, 45.0f);
  const Material plain = s.materials()[1], standard{};
  EXPECT_EQ(plain.name, "plain");
  EXPECT_EQ(plain.diffuse, standard.diffuse);
  EXPECT_EQ(plain.specular, standard.specular);
  EXPECT_EQ(plain.shininess, standard.shininess);
  EXPECT_EQ(plain.emission, standard.emission);
  EXPECT_EQ(plain.mirror, standard.mirror);
  EXPECT_EQ(plain.ior, standard.ior);
  EXPECT_EQ(plain.opacity, standard.opacity);
  EXPECT_EQ(s.spheres()[0].center, Vec3f(0.0f));
  EXPECT_EQ(s.spheres()[0].radius, 1.0f);
  EXPECT_EQ(s.spheres()[0].material, 0u);
  EXPECT_EQ(s.planes()[0].normal, Vec3f(0, 1, 0));
  EXPECT_EQ(s.planes()[0].d, 0.0f);
  expect_same_quadric(s.quadrics()[0].quadric, Quadricf::cylinder(Vec3f(0.0f), 1, 1, 1, 1));
  expect_same_quadric(s.quadrics()[1].quadric, Quadricf::hyperboloid_two_sheets(Vec3f(0.0f), 1, 1, 0.5f, 1, 1));
  expect_same_quadric(s.quadrics()[2].quadric, Quadricf::ellipsoid(Vec3f(0.0f), Vec3f(1.0f)));
}

TEST(JsonScene, PlaneOffsetIsTheSignedDistanceAlongTheNormalisedNormal) {
  const Scene s = json_scene(with_object(R"({"type": "plane", "normal": [0, 0, -2], "offset": 3})"));
  EXPECT_EQ(s.planes()[0].normal, Vec3f(0, 0, -1));
  EXPECT_EQ(s.planes()[0].d, -3.0f);  // n.P + d = 0 holds at P = (0, 0, -3)
}

TEST(JsonScene, NoLightsGivesTheDefaultLightsOfLoadScene) {
  for (const char* lights : {"", R"("lights": [], )"}) {
    const Scene s = json_scene(std::string("{") + lights + R"("objects": [{"type": "sphere", "center": [1, 2, 3]}]})");
    ASSERT_EQ(s.point_lights().size(), 1u) << lights;
    ASSERT_EQ(s.directional_lights().size(), 1u);
    // load.cpp's key light: centre + (0.5, 1.5, 2) r, r = half the bounds' diagonal = sqrt(3).
    expect_near(s.point_lights()[0].position, Vec3f(1, 2, 3) + Vec3f(0.5f, 1.5f, 2.0f) * std::sqrt(3.0f), 1e-5f, "key");
  }
  const Scene lit =
      json_scene(R"({"lights": [{"type": "point", "position": [0, 5, 0]}], "objects": [{"type": "sphere"}]})");
  EXPECT_EQ(lit.point_lights().size(), 1u);
  EXPECT_EQ(lit.point_lights()[0].intensity, Vec3f(1.0f));
  EXPECT_TRUE(lit.directional_lights().empty());
  EXPECT_FALSE(lit.camera().has_value());
}

TEST(JsonScene, ExtensionIsCaseInsensitiveAndLoadJsonSceneAppends) {
  EXPECT_EQ(json_scene(with_object(R"({"type": "sphere"})"), "upper.JSON").spheres().size(), 1u);
  Scene s;
  s.add_sphere({});
  load_json_scene(write_file("append.json", with_object(R"({"type": "sphere", "radius": 2})")), s);
  ASSERT_EQ(s.spheres().size(), 2u);
  EXPECT_EQ(s.spheres()[1].radius, 2.0f);
  EXPECT_TRUE(s.point_lights().empty());  // default lights are load_scene's
}

TEST(JsonScene, MeshMaterialsAreAppendedAndRemappedUnlessOverridden) {
  write_file("meshes/two.mtl", "newmtl a\nKd 1 0 0\nnewmtl b\nKd 0 1 0\n");
  write_file("meshes/two.obj",
             "mtllib two.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nusemtl a\nf 1 2 3\nusemtl b\nf 2 4 3\n");
  const std::string scene = R"json({"materials": {"mine": {}}, "objects": [
      {"type": "mesh", "file": "meshes/two.obj", "transform": {"scale": 2}},
      {"type": "mesh", "file": "meshes/two.obj", "material": "mine"}]})json";
  const Scene s = json_scene(scene, "scene.json");
  // default, mine, then the file's a and b, added once (the second mesh overrides).
  ASSERT_EQ(s.materials().size(), 4u);
  EXPECT_EQ(s.materials()[2].name, "a");
  EXPECT_EQ(s.materials()[3].name, "b");
  ASSERT_EQ(s.meshes().size(), 2u);
  EXPECT_EQ(to_triangle_mesh(s.meshes()[0]).face_materials, (std::vector<uint32_t>{2, 3}));
  EXPECT_EQ(s.meshes()[0].positions[1], Vec3f(2, 0, 0));  // scale as one number
  EXPECT_EQ(s.meshes()[1].material, 1u);
  EXPECT_TRUE(s.meshes()[1].face_materials.empty());
  EXPECT_EQ(s.meshes()[1].positions[1], Vec3f(1, 0, 0));
}

TEST(JsonScene, MeshPathsResolveAgainstTheSceneFolderOrAreAbsolute) {
  const std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  const std::string absolute = write_file("tri.ply", ply);
  write_file("sub/tri.ply", ply);
  const std::string relative = R"({"type": "mesh", "file": "tri.ply", "transform": {"translate": [0, 0, 1]}})";
  const Scene s = json_scene(R"({"objects": [)" + relative + R"(, {"type": "mesh", "file": ")" + absolute + R"("}]})",
                             "sub/scene.json");
  ASSERT_EQ(s.meshes().size(), 2u);
  EXPECT_EQ(s.meshes()[0].positions[2], Vec3f(0, 1, 1));
  EXPECT_EQ(s.meshes()[1].positions[2], Vec3f(0, 1, 0));
  EXPECT_EQ(json_error(R"({"objects": [{"type": "mesh", "file": "sub/tri.ply"}]})", "sub/scene.json"),
            "sub/scene.json: $.objects[0].file: sub/sub/tri.ply: cannot open: No such file or directory");
}

/// A mesh declared once in "meshes" and placed by several "instance" objects.
const std::string kTwoTriangles =
    "mtllib two.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 0 0 1\nusemtl a\nf 1//1 2//1 3//1\nusemtl b\nf 2//1 4//1 3//1\n";

TEST(JsonSceneInstances, AMeshPlacedSeveralTimesIsStoredOnceWithAnInstancePerPlacement) {
  write_file("inst/two.mtl", "newmtl a\nKd 1 0 0\nnewmtl b\nKd 0 1 0\n");
  write_file("inst/two.obj", kTwoTriangles);
  const std::string scene = R"json({"meshes": {"pair": {"file": "two.obj"}}, "objects": [
      {"type": "sphere"},
      {"type": "instance", "mesh": "pair"},
      {"type": "instance", "mesh": "pair", "transform": {"scale": [2, 1, 3],
                                                         "rotate": {"axis": [0, 0, 1], "degrees": 90},
                                                         "translate": [5, 0, 0]}},
      {"type": "instance", "mesh": "pair", "transform": {"translate": [0, 0, -4]}}]})json";
  const Scene s = json_scene(scene, "inst/scene.json");
  ASSERT_EQ(s.meshes().size(), 1u);  // stored once
  EXPECT_TRUE(s.is_instanced(0));
  EXPECT_EQ(s.meshes()[0].positions[1], Vec3f(1, 0, 0));  // in the file's coordinates
  EXPECT_EQ(to_triangle_mesh(s.meshes()[0]).face_materials, (std::vector<uint32_t>{1, 2}));  // the file's a and b, once
  EXPECT_EQ(s.materials().size(), 3u);
  ASSERT_EQ(s.instances().size(), 3u);
  EXPECT_EQ(s.instanced_triangle_count(), 6u);
  EXPECT_EQ(s.spheres().size(), 1u);
  EXPECT_TRUE(s.instances()[0].object_to_world.is_identity());
  // Scale, then rotate 90 degrees about z, then translate: (1, 0, 0) -> (2, 0, 0) -> (0, 2, 0) -> (5, 2, 0).
  expect_near(s.instances()[1].object_to_world.point({1, 0, 0}), {5, 2, 0}, 1e-6f, "instance 1");
  expect_near(s.instances()[1].object_to_world.point({0, 1, 0}), {4, 0, 0}, 1e-6f, "instance 1");
  EXPECT_EQ(s.instances()[2].object_to_world.point({0, 1, 0}), Vec3f(0, 1, -4));
  // The world's bounds hold the three placements.
  expect_near(s.bounds().lo, {-1, -1, -4}, 1e-5f, "bounds");  // the unit sphere reaches -1
  expect_near(s.bounds().hi, {5, 2, 1}, 1e-5f, "bounds");
}

TEST(JsonSceneInstances, AMeshPlacedOnceIsBakedAsAMeshObjectIs) {
  write_file("inst/two.mtl", "newmtl a\nKd 1 0 0\nnewmtl b\nKd 0 1 0\n");
  write_file("inst/two.obj", kTwoTriangles);
  const Scene once = json_scene(R"json({"meshes": {"pair": {"file": "two.obj", "material": "m"}},
      "materials": {"m": {}},
      "objects": [{"type": "instance", "mesh": "pair", "transform": {"translate": [0, 0, 2]}}]})json",
                                "inst/once.json");
  const Scene object = json_scene(R"json({"materials": {"m": {}}, "objects": [
      {"type": "mesh", "file": "two.obj", "material": "m", "transform": {"translate": [0, 0, 2]}}]})json",
                                  "inst/object.json");
  EXPECT_TRUE(once.instances().empty());
  ASSERT_EQ(once.meshes().size(), object.meshes().size());
  EXPECT_FALSE(once.is_instanced(0));
  EXPECT_EQ(to_triangle_mesh(once.meshes()[0]).positions, to_triangle_mesh(object.meshes()[0]).positions);
  EXPECT_EQ(to_triangle_mesh(once.meshes()[0]).normals, to_triangle_mesh(object.meshes()[0]).normals);
  EXPECT_EQ(once.meshes()[0].material, 1u);
}

TEST(JsonSceneInstances, ErrorsNameTheObjectOrTheDeclaration) {
  write_file("inst/two.mtl", "newmtl a\nKd 1 0 0\nnewmtl b\nKd 0 1 0\n");
  write_file("inst/two.obj", kTwoTriangles);
  EXPECT_EQ(json_error(with_object(R"({"type": "instance", "mesh": "tree"})")),
            "scene.json: $.objects[0].mesh: unknown mesh \"tree\" (no meshes are declared)");
  EXPECT_EQ(json_error(R"({"meshes": {"rock": {"file": "r.obj"}, "house": {"file": "h.ply"}},
                          "objects": [{"type": "instance", "mesh": "tree"}]})"),
            "scene.json: $.objects[0].mesh: unknown mesh \"tree\" (meshes: rock, house)");
  EXPECT_EQ(json_error(with_object(R"({"type": "instance"})")), "scene.json: $.objects[0]: missing key \"mesh\"");
  EXPECT_EQ(json_error(R"({"meshes": {"m": {"file": "two.obj", "scale": 2}}, "objects": [{"type": "sphere"}]})"),
            "scene.json: $.meshes.m.scale: unknown key (expected one of: file, material)");
  EXPECT_EQ(json_error(R"({"meshes": {"m": {"file": "two.stl"}}, "objects": [{"type": "sphere"}]})"),
            "scene.json: $.meshes.m.file: \"two.stl\" is not a mesh file (expected .obj or .ply)");
  EXPECT_EQ(json_error(R"({"meshes": {"m": {"file": "two.obj"}}, "objects": [
                          {"type": "instance", "mesh": "m", "material": "x"}]})"),
            "scene.json: $.objects[0].material: unknown key (expected one of: type, mesh, transform)");
  EXPECT_EQ(json_error(R"({"meshes": {"m": {"file": "two.obj"}}, "objects": [
                          {"type": "instance", "mesh": "m", "transform": {"scale": -1}}]})"),
            "scene.json: $.objects[0].transform.scale: -1 is out of range (must be > 0)");
  EXPECT_EQ(json_error(R"({"meshes": {"m": {"file": "missing.obj"}}, "objects": [
                          {"type": "instance", "mesh": "m"}, {"type": "instance", "mesh": "m"}]})"),
            "scene.json: $.meshes.m.file: missing.obj: cannot open: No such file or directory");
  // A placement beyond the coordinate range names the object that places it.
  EXPECT_EQ(json_error(R"({"meshes": {"m": {"file": "inst/two.obj"}}, "objects": [
                          {"type": "instance", "mesh": "m"},
                          {"type": "instance", "mesh": "m", "transform": {"translate": [2e9, 0, 0]}}]})"),
            "scene.json: $.objects[1]: instance 1: mesh 'two' placed at (2e+09, 0, 0) - (2e+09, 1, 0) is outside the "
            "supported coordinate range |x| <= 1073741824 (2^30)");
}

// --- Errors ------------------------------------------------------------------------------------

TEST(JsonSceneErrors, SyntaxErrorsGiveLineAndColumn) {
  EXPECT_EQ(json_error("{\n  \"objects\": [],\n  }\n"),
            "scene.json: line 3, column 3: syntax error while parsing object key - unexpected '}'; "
            "expected string literal");
  EXPECT_EQ(json_error("{\"objects\": [\n"),
            "scene.json: line 2, column 1: syntax error while parsing value - unexpected end of input; "
            "expected '[', '{', or a literal");
  EXPECT_EQ(json_error("{\"objects\": [] // no comments\n}"),
            "scene.json: line 1, column 16: syntax error while parsing object - invalid literal; last read: "
            "'\"objects\": [] /'; expected '}'");
  EXPECT_EQ(json_error(""),
            "scene.json: line 1, column 1: syntax error while parsing value - unexpected end of input; "
            "expected '[', '{', or a literal");
  EXPECT_EQ(json_error(R"({"objects": [{"type": "sphere", "radius": 1e999}]})"),
            "scene.json: number overflow parsing '1e999'");
  EXPECT_EQ(error_of([] { load_scene((scratch() / "absent.json").string()); }),
            "absent.json: cannot open: No such file or directory");
}

TEST(JsonScene, CameraModelsAndLensKeys) {
  const Scene s = json_scene(R"({"camera": {"model": "thin_lens", "aperture": 0.25, "focus_distance": 7,
                                            "fisheye_fov": 200}, "objects": [{"type": "sphere"}]})");
  ASSERT_TRUE(s.camera().has_value());
  EXPECT_EQ(s.camera()->model, CameraModel::thin_lens);
  EXPECT_EQ(s.camera()->aperture, 0.25f);
  EXPECT_EQ(s.camera()->focus_distance, 7.0f);
  EXPECT_EQ(s.camera()->fisheye_fov_degrees, 200.0f);
  EXPECT_EQ(json_error(R"({"camera": {"model": "orthographic"}, "objects": [{"type": "sphere"}]})"),
            "scene.json: $.camera.model: unknown camera model \"orthographic\" (expected one of: pinhole, panoramic, "
            "fisheye, thin_lens)");
  EXPECT_EQ(json_error(R"({"camera": {"aperture": -1}, "objects": [{"type": "sphere"}]})"),
            "scene.json: $.camera.aperture: -1 is out of range (must be >= 0)");
}

TEST(JsonSceneErrors, UnknownKeysListTheExpectedOnes) {
  EXPECT_EQ(json_error(R"({"objects": [{"type": "sphere"}, {"type": "sphere"},
                                      {"type": "sphere", "center": [0, 0, 0], "radus": 2}]})"),
            "scene.json: $.objects[2].radus: unknown key (expected one of: type, center, radius, material)");
  EXPECT_EQ(json_error(R"({"object": []})"),
            "scene.json: $.object: unknown key (expected one of: camera, materials, meshes, lights, objects)");
  EXPECT_EQ(json_error(R"({"camera": {"fov_y": 40}, "objects": []})"),
            "scene.json: $.camera.fov_y: unknown key (expected one of: eye, look_at, up, fov, model, fisheye_fov, "
            "aperture, focus_distance)");
  EXPECT_EQ(json_error(R"({"materials": {"my red": {"colour": [1, 0, 0]}}, "objects": []})"),
            "scene.json: $.materials[\"my red\"].colour: unknown key (expected one of: diffuse, specular, shininess, "
            "emission, mirror, ior, opacity)");
  EXPECT_EQ(json_error(R"({"lights": [{"type": "directional", "position": [0, 1, 0]}], "objects": []})"),
            "scene.json: $.lights[0].position: unknown key (expected one of: type, direction, irradiance)");
  EXPECT_EQ(json_error(with_object(R"({"type": "quadric", "shape": "cone", "radius_a": 1})")),
            "scene.json: $.objects[0].radius_a: unknown key (expected one of: type, shape, center, a, b, half_height, "
            "axis, material)");
  EXPECT_EQ(json_error(with_object(R"({"type": "quadric", "coefficients": {"K": 1}, "clip": {}})")),
            "scene.json: $.objects[0].coefficients.K: unknown key (expected one of: A, B, C, D, E, F, G, H, I, J)");
  EXPECT_EQ(json_error(with_object(R"({"type": "quadric", "coefficients": {"A": 1}, "clip": {"lo": [0, 0, 0]}})")),
            "scene.json: $.objects[0].clip.lo: unknown key (expected one of: min, max)");
  EXPECT_EQ(json_error(with_object(R"({"type": "mesh", "file": "m.obj", "transform": {"rotation": {}}})")),
            "scene.json: $.objects[0].transform.rotation: unknown key (expected one of: scale, rotate, translate)");
  EXPECT_EQ(json_error(with_object(R"({"type": "mesh", "file": "m.obj", "transform": {"rotate": {"angle": 3}}})")),
            "scene.json: $.objects[0].transform.rotate.angle: unknown key (expected one of: axis, degrees)");
}

TEST(JsonSceneErrors, WrongTypesShowTheValueCompactly) {
  EXPECT_EQ(json_error(R"({"camera": {"fov": "wide"}, "objects": []})"),
            "scene.json: $.camera.fov: expected a number, got \"wide\"");
  EXPECT_EQ(json_error(R"([{"type": "sphere"}])"), "scene.json: $: expected an object, got [{\"type\":\"sphere\"}]");
  EXPECT_EQ(json_error(R"({"objects": {"type": "sphere"}})"),
            "scene.json: $.objects: expected an array, got {\"type\":\"sphere\"}");
  EXPECT_EQ(json_error(R"({"objects": [{"type": "sphere"}, 7]})"),
            "scene.json: $.objects[1]: expected an object, got 7");
  EXPECT_EQ(json_error(with_object(R"({"type": 3})")), "scene.json: $.objects[0].type: expected a string, got 3");
  EXPECT_EQ(json_error(with_object(R"({"type": "sphere", "material": ["red"]})")),
            "scene.json: $.objects[0].material: expected a string, got [\"red\"]");
  EXPECT_EQ(json_error(with_object(R"({"type": "sphere", "radius": true})")),
            "scene.json: $.objects[0].radius: expected a number, got true");
  EXPECT_EQ(json_error(R"({"materials": [], "objects": []})"), "scene.json: $.materials: expected an object, got []");
  EXPECT_EQ(json_error(R"({"materials": {"red": 1}, "objects": []})"),
            "scene.json: $.materials.red: expected an object, got 1");
  EXPECT_EQ(json_error(R"({"lights": {}, "objects": []})"), "scene.json: $.lights: expected an array, got {}");
  // Values longer than 40 characters are cut to 37 and "...".
  EXPECT_EQ(
      json_error(with_object(R"({"type": "sphere", "radius": "this radius is described in words, not as a number"})")),
      "scene.json: $.objects[0].radius: expected a number, got \"this radius is described in words, n...");
  // ... never inside a UTF-8 sequence.
  std::string accents;
  for (int i = 0; i < 30; ++i) accents += "\u00e9";
  std::string cut;
  for (int i = 0; i < 17; ++i) cut += "\u00e9";
  EXPECT_EQ(json_error(with_object(R"({"type": "sphere", "radius": "x)" + accents + R"("})")),
            "scene.json: $.objects[0].radius: expected a number, got \"x" + cut + "...");
  EXPECT_EQ(json_error(with_object(R"({"type": "mesh", "file": "m.obj", "transform": {"scale": "big"}})")),
            "scene.json: $.objects[0].transform.scale: expected a number or 3 numbers, got \"big\"");
}

TEST(JsonSceneErrors, VectorsNeedThreeFiniteFloats) {
  EXPECT_EQ(json_error(R"({"camera": {"eye": [1, 2]}, "objects": []})"),
            "scene.json: $.camera.eye: expected 3 numbers, got [1,2]");
  EXPECT_EQ(json_error(R"({"camera": {"eye": [1, "2", 3]}, "objects": []})"),
            "scene.json: $.camera.eye: expected 3 numbers, got [1,\"2\",3]");
  EXPECT_EQ(json_error(R"({"camera": {"up": 1}, "objects": []})"),
            "scene.json: $.camera.up: expected 3 numbers, got 1");
  EXPECT_EQ(json_error(R"({"camera": {"eye": [1, 2, 1e39]}, "objects": []})"),
            "scene.json: $.camera.eye[2]: 1e+39 is out of range (must fit in a 32-bit float)");
  EXPECT_EQ(json_error(with_object(R"({"type": "polygon", "vertices": [[0, 0, 0], [1, 0, 0], [0, 1]]})")),
            "scene.json: $.objects[0].vertices[2]: expected 3 numbers, got [0,1]");
}

TEST(JsonSceneErrors, PositionsOutsideTheCoordinateRangeNameTheirPath) {
  EXPECT_EQ(json_error(R"({"camera": {"eye": [0, 0, 1e19]}, "objects": []})"),
            "scene.json: $.camera.eye: [0,0,1e+19] is out of range (must be within the supported coordinate range "
            "|x| <= 1073741824 = 2^30)");
  EXPECT_EQ(json_error(R"({"camera": {"look_at": [3e38, 0, 0]}, "objects": []})"),
            "scene.json: $.camera.look_at: [3e+38,0,0] is out of range (must be within the supported coordinate range "
            "|x| <= 1073741824 = 2^30)");
  EXPECT_EQ(json_error(R"({"camera": {"model": "thin_lens", "aperture": 2e9}, "objects": []})"),
            "scene.json: $.camera.aperture: 2000000000.0 is out of range (the lens must stay within the supported "
            "coordinate range |x| <= 1073741824 = 2^30)");
  EXPECT_EQ(json_error(with_object(R"({"type": "sphere", "center": [2e9, 0, 0]})")),
            "scene.json: $.objects[0]: sphere at (2e+09, 0, 0) radius 1: its box is outside the supported coordinate "
            "range |x| <= 1073741824 (2^30)");
  EXPECT_EQ(json_error(R"({"lights": [{"type": "point", "position": [0, -2e9, 0]}], "objects": []})"),
            "scene.json: $.lights[0]: point light at (0, -2e+09, 0): outside the supported coordinate range |x| <= "
            "1073741824 (2^30)");
}

TEST(JsonSceneErrors, NestingDeeperThan64LevelsIsRefusedBeforeParsing) {
  // 70,000 levels overflowed the stack when the error path printed the value recursively.
  const std::string deep = R"({"objects": )" + std::string(70000, '[') + std::string(70000, ']') + "}";
  EXPECT_EQ(json_error(deep), "scene.json: line 1, column 76: nesting deeper than 64 levels");
  // Brackets inside strings do not count, escaped quotes do not end a string.
  const std::string in_string = R"({"materials": {"a\"[[[": {}}, "x": ")" + std::string(100, '[') + R"("})";
  EXPECT_EQ(json_error(in_string).find("nesting"), std::string::npos) << json_error(in_string);
}

TEST(JsonSceneErrors, OutOfRangeValuesNameTheRange) {
  EXPECT_EQ(json_error(with_object(R"({"type": "sphere", "radius": -1})")),
            "scene.json: $.objects[0].radius: -1 is out of range (must be > 0)");
  EXPECT_EQ(json_error(R"({"camera": {"fov": 180}, "objects": []})"),
            "scene.json: $.camera.fov: 180 is out of range (must be in (0, 180))");
  EXPECT_EQ(json_error(R"({"camera": {"fov": 0}, "objects": []})"),
            "scene.json: $.camera.fov: 0 is out of range (must be in (0, 180))");
  EXPECT_EQ(json_error(R"({"materials": {"m": {"diffuse": [0.5, -0.1, 0]}}, "objects": []})"),
            "scene.json: $.materials.m.diffuse[1]: -0.1 is out of range (must be >= 0)");
  EXPECT_EQ(json_error(R"({"materials": {"m": {"shininess": -2}}, "objects": []})"),
            "scene.json: $.materials.m.shininess: -2 is out of range (must be >= 0)");
  EXPECT_EQ(json_error(R"({"materials": {"m": {"ior": 0.5}}, "objects": []})"),
            "scene.json: $.materials.m.ior: 0.5 is out of range (must be >= 1)");
  EXPECT_EQ(json_error(R"({"materials": {"m": {"opacity": 1.5}}, "objects": []})"),
            "scene.json: $.materials.m.opacity: 1.5 is out of range (must be in [0, 1])");
  EXPECT_EQ(json_error(R"({"materials": {"m": {"mirror": -0.25}}, "objects": []})"),
            "scene.json: $.materials.m.mirror: -0.25 is out of range (must be in [0, 1])");
  EXPECT_EQ(
      json_error(R"({"lights": [{"type": "point", "position": [0, 1, 0], "intensity": [1, 1, -1]}], "objects": []})"),
      "scene.json: $.lights[0].intensity[2]: -1 is out of range (must be >= 0)");
  EXPECT_EQ(json_error(with_object(R"({"type": "quadric", "shape": "ellipsoid", "radii": [1, 0, 1]})")),
            "scene.json: $.objects[0].radii[1]: 0 is out of range (must be > 0)");
  EXPECT_EQ(json_error(with_object(R"({"type": "quadric", "shape": "paraboloid", "height": -0.5})")),
            "scene.json: $.objects[0].height: -0.5 is out of range (must be > 0)");
  EXPECT_EQ(json_error(with_object(R"({"type": "quadric", "shape": "hyperboloid2", "c": 2, "half_height": 1.5})")),
            "scene.json: $.objects[0].half_height: 1.5 is out of range (must be > c = 2)");
  EXPECT_EQ(json_error(with_object(R"({"type": "mesh", "file": "m.obj", "transform": {"scale": [1, 0, 1]}})")),
            "scene.json: $.objects[0].transform.scale[1]: 0 is out of range (must be > 0)");
  EXPECT_EQ(json_error(with_object(R"({"type": "quadric", "coefficients": {"A": 1, "J": -1},
                                       "clip": {"min": [-1, 2, -1], "max": [1, 1, 1]}})")),
            "scene.json: $.objects[0].clip.max[1]: 1 is out of range (must be >= min[1] = 2)");
  EXPECT_EQ(json_error(with_object(R"({"type": "quadric", "coefficients": {"J": -1}, "clip": {}})")),
            "scene.json: $.objects[0].coefficients: {\"J\":-1} has no x, y or z term (one of A..I must be non-zero)");
}

TEST(JsonSceneErrors, ZeroLengthDirectionsAndDegenerateCamerasAreRefused) {
  EXPECT_EQ(json_error(with_object(R"({"type": "plane", "normal": [0, 0, 0]})")),
            "scene.json: $.objects[0].normal: [0,0,0] is out of range (must have a non-zero length)");
  EXPECT_EQ(json_error(R"({"lights": [{"type": "directional", "direction": [0, 0.0, 0]}], "objects": []})"),
            "scene.json: $.lights[0].direction: [0,0.0,0] is out of range (must have a non-zero length)");
  EXPECT_EQ(
      json_error(with_object(R"({"type": "mesh", "file": "m.obj", "transform": {"rotate": {"axis": [0, 0, 0]}}})")),
      "scene.json: $.objects[0].transform.rotate.axis: [0,0,0] is out of range (must have a non-zero length)");
  EXPECT_EQ(json_error(R"({"camera": {"eye": [0, 3, 8], "look_at": [0, 3, 8]}, "objects": []})"),
            "scene.json: $.camera.look_at: [0,3,8] is out of range (must differ from eye)");
  EXPECT_EQ(json_error(R"({"camera": {"eye": [0, 0, 0]}, "objects": []})"),
            "scene.json: $.camera.eye: [0,0,0] is out of range (must differ from look_at)");
  EXPECT_EQ(json_error(R"({"camera": {"eye": [0, 5, 0]}, "objects": []})"),
            "scene.json: $.camera.up: [0,1,0] is out of range (must not be parallel to look_at - eye)");
  EXPECT_EQ(json_error(R"({"camera": {"up": [0, 0, -2]}, "objects": []})"),
            "scene.json: $.camera.up: [0,0,-2] is out of range (must not be parallel to look_at - eye)");
}

TEST(JsonSceneErrors, PolygonsNeedThreeCoplanarVerticesAndArea) {
  EXPECT_EQ(json_error(with_object(R"({"type": "polygon", "vertices": [[0, 0, 0], [1, 0, 0]]})")),
            "scene.json: $.objects[0].vertices: expected an array of at least 3 vertices, got [[0,0,0],[1,0,0]]");
  EXPECT_EQ(json_error(with_object(R"({"type": "polygon"})")), "scene.json: $.objects[0]: missing key \"vertices\"");
  EXPECT_EQ(json_error(with_object(R"({"type": "polygon", "vertices": [[0, 0, 0], [1, 0, 0], [2, 0, 0]]})")),
            "scene.json: $.objects[0].vertices: [[0,0,0],[1,0,0],[2,0,0]] has zero area (the vertices are collinear)");
  // The first vertex farther than 1e-4 of the box diagonal from the (Newell) plane of them all.
  EXPECT_EQ(json_error(with_object(R"({"type": "polygon", "vertices": [[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 1]]})")),
            "scene.json: $.objects[0].vertices[0]: [0,0,0] is 0.235702 off the polygon's plane (the vertices must be "
            "coplanar)");
  EXPECT_EQ(
      json_scene(with_object(R"({"type": "polygon", "vertices": [[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 1e-4]]})"))
          .polygons()
          .size(),
      1u);
}

TEST(JsonSceneErrors, UnknownNamesListTheKnownOnes) {
  EXPECT_EQ(json_error(R"({"materials": {"red": {}}, "objects": [{"type": "sphere", "material": "red"},
                                                                 {"type": "sphere", "material": "blue"}]})"),
            "scene.json: $.objects[1].material: unknown material \"blue\" (materials: red)");
  EXPECT_EQ(json_error(R"({"materials": {"red": {}, "white": {}}, "objects": [{"type": "plane", "material": "Red"}]})"),
            "scene.json: $.objects[0].material: unknown material \"Red\" (materials: red, white)");
  EXPECT_EQ(json_error(with_object(R"({"type": "sphere", "material": "red"})")),
            "scene.json: $.objects[0].material: unknown material \"red\" (no materials are defined)");
  EXPECT_EQ(json_error(with_object(R"({"type": "cube"})")),
            "scene.json: $.objects[0].type: unknown object type \"cube\" (expected one of: sphere, plane, polygon, "
            "quadric, mesh, instance)");
  EXPECT_EQ(json_error(with_object(R"({"type": "quadric", "shape": "torus"})")),
            "scene.json: $.objects[0].shape: unknown quadric shape \"torus\" (expected one of: ellipsoid, cylinder, "
            "cone, hyperboloid1, hyperboloid2, paraboloid)");
  EXPECT_EQ(json_error(with_object(R"({"type": "quadric", "shape": "cylinder", "axis": "w"})")),
            "scene.json: $.objects[0].axis: unknown axis \"w\" (expected one of: x, y, z)");
  EXPECT_EQ(json_error(R"({"lights": [{"type": "spot"}], "objects": []})"),
            "scene.json: $.lights[0].type: unknown light type \"spot\" (expected one of: point, directional)");
}

TEST(JsonSceneErrors, MissingRequiredKeysAndEmptyScenes) {
  EXPECT_EQ(json_error(R"({"camera": {}})"), "scene.json: $: missing key \"objects\"");
  EXPECT_EQ(json_error(R"({"objects": []})"), "scene.json: $.objects: expected at least one object, got []");
  EXPECT_EQ(json_error(with_object(R"({"radius": 1})")), "scene.json: $.objects[0]: missing key \"type\"");
  EXPECT_EQ(json_error(R"({"lights": [{"type": "point"}], "objects": []})"),
            "scene.json: $.lights[0]: missing key \"position\"");
  EXPECT_EQ(json_error(with_object(R"({"type": "mesh"})")), "scene.json: $.objects[0]: missing key \"file\"");
  EXPECT_EQ(json_error(with_object(R"({"type": "quadric"})")),
            "scene.json: $.objects[0]: missing key \"shape\" (or \"coefficients\")");
  EXPECT_EQ(json_error(with_object(R"({"type": "quadric", "shape": "cone", "coefficients": {}})")),
            "scene.json: $.objects[0]: expected \"shape\" or \"coefficients\", not both");
  EXPECT_EQ(json_error(with_object(R"({"type": "quadric", "coefficients": {"A": 1}})")),
            "scene.json: $.objects[0]: missing key \"clip\"");
  EXPECT_EQ(json_error(with_object(R"({"type": "quadric", "coefficients": {"A": 1}, "clip": {"min": [0, 0, 0]}})")),
            "scene.json: $.objects[0].clip: missing key \"max\"");
}

TEST(JsonSceneErrors, MeshFileProblemsCarryTheLoadersMessage) {
  EXPECT_EQ(json_error(R"({"objects": [{"type": "sphere"}, {"type": "sphere"}, {"type": "sphere"}, {"type": "sphere"},
                                      {"type": "mesh", "file": "missing.obj"}]})"),
            "scene.json: $.objects[4].file: missing.obj: cannot open: No such file or directory");
  EXPECT_EQ(json_error(with_object(R"({"type": "mesh", "file": "model.stl"})")),
            "scene.json: $.objects[0].file: \"model.stl\" is not a mesh file (expected .obj or .ply)");
  write_file("empty.obj", "v 0 0 0\n");
  EXPECT_EQ(json_error(with_object(R"({"type": "mesh", "file": "empty.obj"})")),
            "scene.json: $.objects[0].file: empty.obj: the file has no triangles");
  // What the Scene itself refuses comes back with the object's path.
  write_file("tri.obj", "v 0 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\n");
  EXPECT_EQ(json_error(with_object(R"({"type": "mesh", "file": "tri.obj", "transform": {"scale": [3e38, 1, 1]}})")),
            "scene.json: $.objects[0]: mesh 'tri': vertex 1 has a non-finite coordinate");
  write_file("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
  EXPECT_EQ(json_error(with_object(R"({"type": "mesh", "file": "bad.obj"})")),
            "scene.json: $.objects[0].file: bad.obj: line 4: vertex index 9 is past the file's 3 vertices");
}

}  // namespace
}  // namespace rp

namespace rp {
namespace {

/// Random JSON text: nested objects and arrays, keys drawn from a few so that they repeat.
std::string random_json(std::mt19937& rng, int depth) {
  const int kind = int(rng() % (depth > 3 ? 4 : 6));
  switch (kind) {
    case 0:
      return std::to_string(int(rng() % 2000) - 1000);
    case 1:
      return std::to_string(double(rng() % 100000) / 7.0);
    case 2:
      return "\"s" + std::to_string(rng() % 5) + "\\u00e9\"";
    case 3:
      return rng() % 2 ? "true" : "null";
    case 4: {
      std::string a = "[";
      for (int i = 0, n = int(rng() % 5); i < n; ++i) a += (i ? "," : "") + random_json(rng, depth + 1);
      return a + "]";
    }
    default: {
      std::string o = "{";
      for (int i = 0, n = int(rng() % 6); i < n; ++i)
        o += (i ? ",\"k" : "\"k") + std::to_string(rng() % 4) + "\":" + random_json(rng, depth + 1);
      return o + "}";
    }
  }
}

TEST(OrderedJson, GivesNlohmannsDocumentAndErrors) {
  // The linear-time parse against nlohmann's own: the same keys in the same order (a repeated
  // key in its first place with its last value), the same values, the same error offsets.
  std::mt19937 rng(7);
  for (int i = 0; i < 2000; ++i) {
    const std::string text = random_json(rng, 0);
    const nlohmann::ordered_json want = nlohmann::ordered_json::parse(text);
    const nlohmann::ordered_json got = parse_ordered_json(text);
    ASSERT_EQ(got.dump(), want.dump()) << text;
  }
  for (const std::string bad :
       {"", "{", "{\"a\":1,}", "[1 2]", "{\"a\" 1}", "1 2", "/* c */ 1", "[1e999]", "\"\\x\""}) {
    size_t want = 0, got = 0;
    std::string want_what, got_what;
    try {
      const nlohmann::ordered_json doc = nlohmann::ordered_json::parse(bad);
      ADD_FAILURE() << bad << " parsed as " << doc.dump();
    } catch (const nlohmann::ordered_json::exception& e) {
      want_what = e.what();
      if (const auto* p = dynamic_cast<const nlohmann::ordered_json::parse_error*>(&e)) want = p->byte;
    }
    try {
      const nlohmann::ordered_json doc = parse_ordered_json(bad);
      ADD_FAILURE() << bad << " parsed as " << doc.dump();
    } catch (const nlohmann::ordered_json::exception& e) {
      got_what = e.what();
      if (const auto* p = dynamic_cast<const nlohmann::ordered_json::parse_error*>(&e)) got = p->byte;
    }
    EXPECT_FALSE(want_what.empty()) << bad;
    EXPECT_EQ(got_what, want_what) << bad;
    EXPECT_EQ(got, want) << bad;
  }
}

/// A scene of n materials and n meshes placed once each, and the seconds its load takes (the
/// median of three).
double load_seconds_of_names(size_t n) {
  std::string text = "{\"materials\": {";
  for (size_t i = 0; i < n; ++i) text += cat(i ? ", " : "", "\"m", i, "\": {}");
  text += "}, \"meshes\": {";
  for (size_t i = 0; i < n; ++i) text += cat(i ? ", " : "", "\"k", i, "\": {\"file\": \"tri.obj\"}");
  text += "}, \"objects\": [";
  for (size_t i = 0; i < n; ++i) text += cat(i ? ", " : "", "{\"type\": \"instance\", \"mesh\": \"k", i, "\"}");
  text += cat(", {\"type\": \"sphere\", \"material\": \"m", n - 1, "\"}]}");
  test::write_file("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const std::string path = test::write_file(cat("names-", n, ".json"), text);
  std::vector<double> seconds;
  for (int run = 0; run < 3; ++run) {
    const auto start = std::chrono::steady_clock::now();
    const Scene scene = load_scene(path);
    seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    EXPECT_EQ(scene.materials().size(), n + 1);
    EXPECT_EQ(scene.materials().back().name, cat("m", n - 1)) << "ids follow the file's order";
  }
  std::sort(seconds.begin(), seconds.end());
  return seconds[1];
}

TEST(JsonScene, LoadingTimeGrowsLinearlyWithTheNamesAFileDeclares) {
  // A complexity check, not a speed limit: four times the names must take well under the 16
  // times a quadratic step gives (materials and meshes looked up by name, keys inserted into
  // ordered objects); the two sizes are timed in one run of one process.
  const double small = load_seconds_of_names(10000), large = load_seconds_of_names(40000);
  EXPECT_LT(large / small, 8.0) << "10000 names: " << small << " s, 40000 names: " << large << " s";
}

}  // namespace
}  // namespace rp
