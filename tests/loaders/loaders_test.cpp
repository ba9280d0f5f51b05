/// Scene-file loaders: OBJ (+MTL) through tinyobjloader, PLY by hand, load_scene dispatch.
/// Small files are written to a scratch folder by the tests themselves; the real models of
/// RAYPACK_SHARED_SCENES (CMake; ../shared/scenes by default) are checked against the triangle
/// counts of its README when present.

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "engine/error.h"
#include "engine/loaders/load.h"
#include "scratch.h"
#include "tests/support/error_of.h"

#ifndef RP_SHARED_SCENES
#define RP_SHARED_SCENES "../shared/scenes"
#endif

namespace rp {
namespace {

namespace fs = std::filesystem;
using test::error_of;

using test::scratch;
using test::write_file;

Scene obj_scene(const std::string& name, const std::string& text) {
  Scene scene;
  load_obj(write_file(name, text), scene);
  return scene;
}

Scene ply_scene(const std::string& name, const std::string& bytes) {
  Scene scene;
  load_ply(write_file(name, bytes), scene);
  return scene;
}

std::string obj_error(const std::string& name, const std::string& text) {
  const std::string path = write_file(name, text);
  return error_of([&] {
    Scene s;
    load_obj(path, s);
  });
}

std::string ply_error(const std::string& name, const std::string& bytes) {
  const std::string path = write_file(name, bytes);
  return error_of([&] {
    Scene s;
    load_ply(path, s);
  });
}

std::string path_of(const std::string& name) { return (scratch() / name).string(); }

Vec3d tri_cross(const TriangleMesh& m, uint32_t t) {
  const Vec3d a(m.vertex(t, 0)), b(m.vertex(t, 1)), c(m.vertex(t, 2));
  return cross(b - a, c - a);
}

// --- OBJ ---------------------------------------------------------------------------------------

TEST(ObjLoader, QuadBecomesTwoTrianglesOverItsFourVertices) {
  const Scene s = obj_scene("quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n");
  ASSERT_EQ(s.meshes().size(), 1u);
  const TriangleMesh& m = s.meshes()[0];
  EXPECT_EQ(m.triangle_count(), 2u);
  EXPECT_EQ(m.positions.size(), 4u);
  // A square: both diagonals are equally short, so the fan from corner 0.
  EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3}));
  EXPECT_DOUBLE_EQ(0.5 * (length(tri_cross(m, 0)) + length(tri_cross(m, 1))), 1.0);
  EXPECT_GT(tri_cross(m, 0).z, 0.0);
  EXPECT_GT(tri_cross(m, 1).z, 0.0);
}

TEST(ObjLoader, ConvexQuadSplitsAlongItsShorterDiagonal) {
  // A rhombus whose 2-4 diagonal (length 2) is shorter than its 1-3 one (length 6).
  const Scene s = obj_scene("rhombus.obj", "v -3 0 0\nv 0 -1 0\nv 3 0 0\nv 0 1 0\nf 1 2 3 4\n");
  EXPECT_EQ(s.meshes()[0].indices, (std::vector<uint32_t>{0, 1, 3, 1, 2, 3}));
}

/// 2D point-in-polygon by crossings (the polygon projected on the plane of axes a1, a2).
bool inside(const std::vector<Vec3d>& poly, const Vec3d& p, int a1, int a2) {
  bool in = false;
  for (size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const double xi = poly[i][a1], yi = poly[i][a2], xj = poly[j][a1], yj = poly[j][a2];
    if ((yi > p[a2]) != (yj > p[a2]) && p[a1] < (xj - xi) * (p[a2] - yi) / (yj - yi) + xi) in = !in;
  }
  return in;
}

TEST(ObjLoader, NonConvexPolygonsGiveNMinusTwoTrianglesInsideThePolygon) {
  using P = std::vector<std::pair<double, double>>;
  // tinyobjloader 2.0.0rc10's own triangulation gets each of these wrong once moved off the
  // origin (and the arrow quad everywhere): the loader ear-clips them itself.
  const std::vector<std::pair<std::string, P>> shapes = {
      {"arrow", {{0, 0}, {10, 1}, {0, 2}, {1, 1}}},
      {"L", {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}}},
      {"U", {{0, 0}, {3, 0}, {3, 3}, {2, 3}, {2, 1}, {1, 1}, {1, 3}, {0, 3}}},
      {"star",
       {{0, 3}, {1, 1}, {3, 1}, {1.5, -0.5}, {2.5, -3}, {0, -1.5}, {-2.5, -3}, {-1.5, -0.5}, {-3, 1}, {-1, 1}}},
      {"comb", {{0, 0}, {5, 0}, {5, 2}, {4, 2}, {4, 1}, {3, 1}, {3, 2}, {2, 2}, {2, 1}, {1, 1}, {1, 2}, {0, 2}}}};
  for (const auto& [name, pts] : shapes)
    for (int plane = 0; plane < 3; ++plane)
      for (bool clockwise : {false, true}) {
        SCOPED_TRACE(name + " in plane " + std::to_string(plane) + (clockwise ? " clockwise" : " counter-clockwise"));
        // Embed in the plane normal to axis `plane`, moved away from the origin.
        std::vector<Vec3d> poly;
        for (const auto& [x, y] : pts) {
          Vec3d p{5.0, 5.0, 5.0};
          p[(plane + 1) % 3] += x - 10.0;
          p[(plane + 2) % 3] += y + 7.0;
          poly.push_back(p);
        }
        if (clockwise) std::reverse(poly.begin(), poly.end());
        std::string text;
        for (const Vec3d& p : poly) text += cat("v ", p.x, " ", p.y, " ", p.z, "\n");
        text += "f";
        for (size_t i = 0; i < poly.size(); ++i) text += cat(" ", i + 1);
        text += "\n";
        const Scene s = obj_scene("polygon.obj", text);
        const TriangleMesh& m = s.meshes()[0];
        ASSERT_EQ(m.triangle_count(), poly.size() - 2);

        Vec3d newell{0.0};
        for (size_t i = 0; i < poly.size(); ++i) newell += cross(poly[i], poly[(i + 1) % poly.size()]);
        const double polygon_area = 0.5 * length(newell);
        double area = 0.0;
        for (uint32_t t = 0; t < m.triangle_count(); ++t) {
          const Vec3d c = tri_cross(m, t);
          area += 0.5 * length(c);
          EXPECT_GT(dot(c, newell), 0.0) << "triangle " << t << " is flipped against the polygon";
          const Vec3d centroid = (Vec3d(m.vertex(t, 0)) + Vec3d(m.vertex(t, 1)) + Vec3d(m.vertex(t, 2))) / 3.0;
          EXPECT_TRUE(inside(poly, centroid, (plane + 1) % 3, (plane + 2) % 3))
              << "triangle " << t << " lies outside the polygon";
        }
        EXPECT_NEAR(area, polygon_area, 1e-5 * polygon_area) << "the triangles do not tile the polygon";
      }
}

TEST(ObjLoader, NegativeIndicesCountBackFromTheLatestVertex) {
  const Scene s = obj_scene("negative.obj",
                            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n"
                            "v 5 0 0\nv 6 0 0\nv 5 1 0\nf -3 -2 -1\nf 1 -6 3\n");
  const TriangleMesh& m = s.meshes()[0];
  ASSERT_EQ(m.triangle_count(), 3u);
  EXPECT_EQ(m.vertex(0, 1), Vec3f(1, 0, 0));
  EXPECT_EQ(m.vertex(1, 0), Vec3f(5, 0, 0));
  EXPECT_EQ(m.vertex(1, 2), Vec3f(5, 1, 0));
  EXPECT_EQ(m.vertex(2, 1), Vec3f(0, 0, 0));  // -6 from the 6th vertex is the first
}

const char* const kTwoGroupObj =
    "mtllib two.mtl\n"
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\n"
    "g first\nusemtl red\nf 1 2 3 4\n"
    "g second\nusemtl blue\nf 1 2 5\nusemtl red\nf -1 -2 -4\n";
const char* const kTwoMtl = "newmtl red\nKd 1 0 0\n\nnewmtl blue\nKd 0 0 1\n";

std::string crlf(const std::string& lf) {
  std::string out;
  for (char c : lf) out += c == '\n' ? std::string("\r\n") : std::string(1, c);
  return out;
}

void expect_same_meshes(const Scene& a, const Scene& b) {
  ASSERT_EQ(a.meshes().size(), b.meshes().size());
  for (size_t i = 0; i < a.meshes().size(); ++i) {
    const TriangleMesh &x = a.meshes()[i], &y = b.meshes()[i];
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.positions, y.positions);
    EXPECT_EQ(x.indices, y.indices);
    EXPECT_EQ(x.normals, y.normals);
    EXPECT_EQ(x.uvs, y.uvs);
    EXPECT_EQ(x.face_materials, y.face_materials);
    EXPECT_EQ(x.material, y.material);
  }
}

TEST(ObjLoader, CrlfLineEndingsReadLikeLf) {
  write_file("two.mtl", crlf(kTwoMtl));
  const Scene with_crlf = obj_scene("crlf.obj", crlf(kTwoGroupObj));
  write_file("two.mtl", kTwoMtl);
  const Scene with_lf = obj_scene("lf.obj", kTwoGroupObj);
  expect_same_meshes(with_crlf, with_lf);
  ASSERT_EQ(with_crlf.materials().size(), 3u);
  EXPECT_EQ(with_crlf.materials()[1].name, "red");  // no '\r' left in names
  EXPECT_EQ(with_crlf.materials()[2].name, "blue");
  EXPECT_EQ(with_crlf.materials()[2].diffuse, Vec3f(0, 0, 1));
  EXPECT_EQ(with_crlf.meshes()[0].name, "first");
  EXPECT_EQ(with_crlf.meshes()[1].name, "second");
}

TEST(ObjLoader, OneMaterialPerMeshSetsMaterialSeveralSetFaceMaterials) {
  write_file("two.mtl", kTwoMtl);
  const Scene s = obj_scene("two.obj", kTwoGroupObj);
  ASSERT_EQ(s.meshes().size(), 2u);
  EXPECT_EQ(s.meshes()[0].material, 1u);
  EXPECT_TRUE(s.meshes()[0].face_materials.empty());
  EXPECT_EQ(s.meshes()[1].face_materials, (std::vector<uint32_t>{2, 1}));
}

TEST(ObjLoader, NormalsAndUvsAreKeptOnlyWhenEveryCornerHasOne) {
  const Scene s = obj_scene("attributes.obj",
                            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\nvn 0 1 0\n"
                            "g all\nf 1/1/1 2/2/1 3/3/1\n"
                            "g uvs_only\nf 1/1/1 2/2 3/3/1\n"
                            "g normals_only\nf 1//2 2//2 3/3/2\n"
                            "g none\nf 1 2/2 3//1\n");
  ASSERT_EQ(s.meshes().size(), 4u);
  const TriangleMesh &all = s.meshes()[0], &uvs = s.meshes()[1], &normals = s.meshes()[2], &none = s.meshes()[3];
  ASSERT_EQ(all.normals.size(), 3u);
  ASSERT_EQ(all.uvs.size(), 3u);
  EXPECT_EQ(all.normals[1], Vec3f(0, 0, 1));
  EXPECT_EQ(all.uvs[2], (Vec2f{0, 1}));
  EXPECT_TRUE(uvs.normals.empty());
  EXPECT_EQ(uvs.uvs.size(), 3u);
  EXPECT_EQ(normals.normals.size(), 3u);
  EXPECT_EQ(normals.normals[0], Vec3f(0, 1, 0));
  EXPECT_TRUE(normals.uvs.empty());
  EXPECT_TRUE(none.normals.empty());
  EXPECT_TRUE(none.uvs.empty());

  const Scene plain = obj_scene("plain.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  EXPECT_TRUE(plain.meshes()[0].normals.empty());
  EXPECT_TRUE(plain.meshes()[0].uvs.empty());
}

TEST(ObjLoader, CornersWithTheSameIndexTripleShareOneVertex) {
  // Two quads on a 3x2 grid share an edge: 6 vertices, not 8.
  const Scene grid = obj_scene("grid.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nv 1 1 0\nv 2 1 0\nf 1 2 5 4\nf 2 3 6 5\n");
  EXPECT_EQ(grid.meshes()[0].positions.size(), 6u);
  // One position with two normals becomes two vertices; the same triple stays one.
  const Scene split = obj_scene("split.obj",
                                "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvn 0 0 1\nvn 0 1 0\n"
                                "f 1//1 2//1 3//1\nf 1//2 4//2 2//2\nf 1//1 3//1 4//1\n");
  const TriangleMesh& m = split.meshes()[0];
  EXPECT_EQ(m.positions.size(), 7u);  // (1,1) (2,1) (3,1), then (1,2) (4,2) (2,2), then (4,1)
  EXPECT_EQ(m.indices[0], m.indices[6]);  // corner 1//1 shared by faces 1 and 3
  EXPECT_NE(m.indices[0], m.indices[3]);  // 1//1 and 1//2 differ
  EXPECT_EQ(m.positions[m.indices[0]], m.positions[m.indices[3]]);
}

TEST(ObjLoader, UnreferencedVerticesAreDropped) {
  const Scene s = obj_scene("unreferenced.obj", "v 0 0 0\nv 9 9 9\nv 1 0 0\nv 8 8 8\nv 0 1 0\nf 1 3 5\n");
  const TriangleMesh& m = s.meshes()[0];
  EXPECT_EQ(m.positions, (std::vector<Vec3f>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}));
  EXPECT_EQ(s.bounds(), Box3f(Vec3f(0, 0, 0), Vec3f(1, 1, 0)));
}

TEST(ObjLoader, MtlFieldsMapToTheMaterial) {
  write_file("fields.mtl",
             "newmtl mirror\nKd 0.1 0.2 0.3\nKs 0.4 0.5 0.6\nNs 50\nKe 1 2 3\nNi 1.5\nd 0.25\nillum 3\n"
             "newmtl fresnel\nKs 0.2 0.2 0.8\nillum 5\n"
             "newmtl glass\nKs 1 1 1\nNi 1.33\nd 0.1\nillum 7\n"
             "newmtl plastic\nKd 0.5 0.5 0.5\nKs 0.9 0.9 0.9\nillum 2\n"
             "newmtl unset\nNi 0\n");
  const Scene s = obj_scene("fields.obj",
                            "mtllib fields.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n"
                            "usemtl mirror\nf 1 2 3\nusemtl fresnel\nf 1 2 3\nusemtl glass\nf 1 2 3\n"
                            "usemtl plastic\nf 1 2 3\nusemtl unset\nf 1 2 3\n");
  ASSERT_EQ(s.materials().size(), 6u);
  const Material& mirror = s.materials()[1];
  EXPECT_EQ(mirror.name, "mirror");
  EXPECT_EQ(mirror.diffuse, Vec3f(0.1f, 0.2f, 0.3f));
  EXPECT_EQ(mirror.specular, Vec3f(0.4f, 0.5f, 0.6f));
  EXPECT_FLOAT_EQ(mirror.shininess, 50.0f);
  EXPECT_EQ(mirror.emission, Vec3f(1, 2, 3));
  EXPECT_FLOAT_EQ(mirror.ior, 1.5f);
  EXPECT_FLOAT_EQ(mirror.opacity, 0.25f);
  EXPECT_FLOAT_EQ(mirror.mirror, 0.5f);  // illum 3: mean of Ks
  EXPECT_FLOAT_EQ(s.materials()[2].mirror, 0.4f);  // illum 5: mean of Ks
  const Material& glass = s.materials()[3];
  EXPECT_FLOAT_EQ(glass.mirror, 0.0f);  // illum 7: left to d and Ni
  EXPECT_FLOAT_EQ(glass.ior, 1.33f);
  EXPECT_FLOAT_EQ(glass.opacity, 0.1f);
  EXPECT_FLOAT_EQ(s.materials()[4].mirror, 0.0f);  // illum 2: no mirror
  const Material& unset = s.materials()[5];      // what tinyobj fills in
  EXPECT_EQ(unset.diffuse, Vec3f(0.0f));
  EXPECT_FLOAT_EQ(unset.shininess, 1.0f);
  EXPECT_FLOAT_EQ(unset.ior, 1.0f);  // Ni 0 reads as 1
  EXPECT_FLOAT_EQ(unset.opacity, 1.0f);
  EXPECT_EQ(s.meshes()[0].face_materials, (std::vector<uint32_t>{1, 2, 3, 4, 5}));
}

TEST(ObjLoader, MissingMtlLoadsGeometryWithOneWarningLine) {
  const std::string path = write_file("nomtl.obj", "mtllib missing.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n");
  Scene s;
  testing::internal::CaptureStderr();
  load_obj(path, s);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(err, "raypack: warning: " + path + ": Material file [ missing.mtl ] not found in a path : " +
                     scratch().string() + "/ (and 2 more warnings)\n");  // tinyobj adds the '/'
  EXPECT_EQ(s.triangle_count(), 1u);
  EXPECT_EQ(s.materials().size(), 1u);
  EXPECT_EQ(s.meshes()[0].material, 0u);
}

TEST(ObjLoader, FaceOfTwoVerticesIsSkippedWithTinyobjWarning) {
  // tinyobjloader drops faces of fewer than 3 corners with the warning "Degenerated face found"
  // and loads the rest; the loader keeps that behaviour and passes the warning on.
  const std::string path = write_file("two_corners.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\nf 1 2 3\n");
  Scene s;
  testing::internal::CaptureStderr();
  load_obj(path, s);
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "raypack: warning: " + path + ": Degenerated face found\n");
  EXPECT_EQ(s.triangle_count(), 1u) << "the 2-corner face should be skipped, the triangle kept";
}

TEST(ObjLoader, GroupsAndObjectsBecomeNamedMeshes) {
  const Scene s = obj_scene("named.obj",
                            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\no body\nf 1 2 3\ng wheel\nf 1 2 3\nf 3 2 1\n");
  ASSERT_EQ(s.meshes().size(), 3u);
  EXPECT_EQ(s.meshes()[0].name, "named");  // before any g/o: the file's stem
  EXPECT_EQ(s.meshes()[1].name, "body");
  EXPECT_EQ(s.meshes()[2].name, "wheel");
  EXPECT_EQ(s.meshes()[2].triangle_count(), 2u);
}

TEST(ObjLoader, DegenerateTrianglesAreKept) {
  const Scene s = obj_scene("degenerate.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\n");
  EXPECT_EQ(s.triangle_count(), 2u);
  EXPECT_EQ(s.degenerate_triangle_count(), 1u);
}

TEST(ObjLoader, EveryNumberIsParsedStrictlyWithItsLine) {
  // tinyobjloader alone reads these as 0, as a prefix, or wrapped (4294967299 -> 3).
  const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  const std::pair<std::string, std::string> cases[] = {
      {"v 1 abc 0\n" + tri + "f 2 3 4\n", "line 1: 'abc' is not a number"},
      {tri + "v 1x 0 0\nf 1 2 3\n", "line 4: '1x' is not a number"},
      {tri + "v 1e 0 0\nf 1 2 3\n", "line 4: '1e' is not a number"},
      {tri + "v nan 0 0\nf 1 2 3\n", "line 4: 'nan' is not a number"},
      {tri + "v inf 0 0\nf 1 2 3\n", "line 4: 'inf' is not a number"},
      {tri + "v 0x10 0 0\nf 1 2 3\n", "line 4: '0x10' is not a number"},
      {tri + "v . 0 0\nf 1 2 3\n", "line 4: '.' is not a number"},
      {tri + "v 1e39 0 0\nf 1 2 3\n", "line 4: '1e39' is out of the float range"},
      {tri + "v 0 2e9 0\nf 1 2 3\n", "line 4: vertex coordinate 2e9 is outside the supported coordinate range |x| <= 1073741824 (2^30)"},
      {tri + "v 1 2\nf 1 2 3\n", "line 4: a vertex ('v') takes 3 to 7 numbers, got 2"},
      {tri + "vn 0 0\nf 1 2 3\n", "line 4: a normal ('vn') takes 3 numbers, got 2"},
      {tri + "vn 0 0 1x\nf 1 2 3\n", "line 4: '1x' is not a number"},
      {tri + "vt 0 q\nf 1 2 3\n", "line 4: 'q' is not a number"},
      {tri + "f 1 2 4294967299\n", "line 4: vertex index 4294967299 is out of range"},
      {tri + "f 1 2 3abc\n", "line 4: '3abc' is not an index (i, i/j, i//k or i/j/k)"},
      {tri + "f 1 2 -4\n", "line 4: relative vertex index -4 reaches before the first (3 read so far)"},
      {tri + "f 1 2 3/\n", "line 4: '3/' is not an index (i, i/j, i//k or i/j/k)"},
      {tri + "f 1 2 3/1/1/1\n", "line 4: '3/1/1/1' has more than 3 indices"},
      {tri + "vt 0 0\nf 1/1 2/1 3/x\n", "line 5: '3/x' is not an index (i, i/j, i//k or i/j/k)"},
      {tri + "l 1 2 0\n", "line 4: vertex index 0 is 0 (OBJ counts from 1)"},
      // Line numbers count lines as tinyobj does: "\r\n" and a lone "\r" end one line each.
      {"v 0 0 0\r\nv 1 0 0\r\nv 0 one 0\r\nf 1 2 3\r\n", "line 3: 'one' is not a number"},
      {"v 0 0 0\rv 1 0 0\rv 0 one 0\rf 1 2 3\r", "line 3: 'one' is not a number"},
  };
  for (const auto& [text, message] : cases) EXPECT_EQ(obj_error("strict.obj", text), path_of("strict.obj") + ": " + message) << text;
  // What tinyobj reads and the check accepts: signs, fractions alone, exponents, w and colours.
  const Scene s = obj_scene("fine.obj", "v +1 -.5 1.e0\nv 1.5E+2 0 0 1\nv 0 1 0 0.5 0.5 0.5\nvt .5\nvn 0 0 +1\nf 1/1/1 2//1 -1\n");
  EXPECT_EQ(s.triangle_count(), 1u);
  EXPECT_EQ(s.meshes()[0].positions[0], Vec3f(1, -0.5f, 1));
}

TEST(ObjLoader, BadFilesThrowOneLineErrors) {
  const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  EXPECT_EQ(obj_error("nonfinite.obj", "v 0 0 0\nv 1e999 0 0\nv 0 1 0\nf 1 2 3\n"),
            path_of("nonfinite.obj") + ": line 2: '1e999' is out of the float range");
  EXPECT_EQ(obj_error("range.obj", tri + "f 1 2 3\nf 1 2 9\n"), path_of("range.obj") + ": line 5: vertex index 9 is past the file's 3 vertices");
  EXPECT_EQ(obj_error("normal.obj", tri + "vn 0 0 1\nf 1//1 2//1 3//7\n"),
            path_of("normal.obj") + ": line 5: normal index 7 is past the file's 1 normals");
  EXPECT_EQ(obj_error("uv.obj", tri + "vt 0 0\nf 1/1 2/4 3/1\n"),
            path_of("uv.obj") + ": line 5: texture coordinate index 4 is past the file's 1 texture coordinates");
  EXPECT_EQ(obj_error("zero.obj", tri + "f 0 1 2\n"),
            path_of("zero.obj") + ": line 4: vertex index 0 is 0 (OBJ counts from 1)");
  std::string big = "g disc\n";
  for (int i = 0; i < 300; ++i) big += cat("v ", std::cos(i * 2 * kPi / 300), " ", std::sin(i * 2 * kPi / 300), " 0\n");
  big += "f";
  for (int i = 1; i <= 300; ++i) big += cat(" ", i);
  EXPECT_EQ(obj_error("disc.obj", big + "\n"),
            path_of("disc.obj") +
                ": mesh 'disc' has a face of more than 255 corners, which tinyobjloader 2.0.0rc10 cannot represent");
  write_file("bad.mtl", "newmtl shiny\nNs -1\n");
  EXPECT_EQ(obj_error("badmtl.obj", "mtllib bad.mtl\n" + tri + "usemtl shiny\nf 1 2 3\n"),
            path_of("badmtl.obj") + ": material 'shiny': shininess -1 must be >= 0");
  EXPECT_EQ(error_of([] {
              Scene s;
              load_obj(path_of("absent.obj"), s);
            }),
            path_of("absent.obj") + ": cannot open: No such file or directory");
  fs::create_directories(scratch() / "folder.obj");
  EXPECT_EQ(error_of([] {
              Scene s;
              load_obj(path_of("folder.obj"), s);
            }),
            path_of("folder.obj") + ": cannot read: not a regular file (a directory)");
}

// --- PLY ---------------------------------------------------------------------------------------

enum class PlyFormat { ascii, little_endian, big_endian };

/// Writes a PLY file: header lines, then values typed as declared.
class PlyWriter {
 public:
  explicit PlyWriter(PlyFormat f) : format_(f) {}

  PlyWriter& header(const std::string& line) {
    header_ += line + "\n";
    return *this;
  }
  /// One value of PLY type `type` (ascii: a token; binary: its bytes in the file's byte order).
  PlyWriter& put(const std::string& type, double v) {
    if (format_ == PlyFormat::ascii) {
      char buf[64];
      if (type == "float" || type == "float32")
        std::snprintf(buf, sizeof buf, "%.9g ", v);
      else if (type == "double" || type == "float64")
        std::snprintf(buf, sizeof buf, "%.17g ", v);
      else
        std::snprintf(buf, sizeof buf, "%lld ", static_cast<long long>(v));
      body_ += buf;
      return *this;
    }
    if (type == "char" || type == "int8") bytes(int8_t(v));
    else if (type == "uchar" || type == "uint8") bytes(uint8_t(v));
    else if (type == "short" || type == "int16") bytes(int16_t(v));
    else if (type == "ushort" || type == "uint16") bytes(uint16_t(v));
    else if (type == "int" || type == "int32") bytes(int32_t(v));
    else if (type == "uint" || type == "uint32") bytes(uint32_t(int64_t(v)));
    else if (type == "float" || type == "float32") bytes(float(v));
    else bytes(v);
    return *this;
  }
  /// Ends an element item (a new line in ascii).
  PlyWriter& end_item() {
    if (format_ == PlyFormat::ascii && !body_.empty() && body_.back() == ' ') body_.back() = '\n';
    return *this;
  }
  std::string str() const {
    const char* name = format_ == PlyFormat::ascii           ? "ascii"
                       : format_ == PlyFormat::little_endian ? "binary_little_endian"
                                                             : "binary_big_endian";
    return std::string("ply\nformat ") + name + " 1.0\n" + header_ + "end_header\n" + body_;
  }

 private:
  template <typename T>
  void bytes(T v) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof v);
    const bool big = format_ == PlyFormat::big_endian;
    if (big == (std::endian::native == std::endian::little)) std::reverse(b, b + sizeof(T));
    body_.append(b, sizeof(T));
  }

  PlyFormat format_;
  std::string header_, body_;
};

const std::vector<Vec3f> kCubeVertices = {{-1.5f, -1, 0.25f}, {2.25f, -1, 0.25f}, {2.25f, 3, 0.25f},
                                          {-1.5f, 3, 0.25f},  {-1.5f, -1, 4.5f},  {2.25f, -1, 4.5f},
                                          {2.25f, 3, 4.5f},   {-1.5f, 3, 4.5f}};
const std::vector<Vec3f> kCubeNormals = {{-0.5f, -0.5f, -0.5f}, {0.5f, -0.5f, -0.5f}, {0.5f, 0.5f, -0.5f},
                                         {-0.5f, 0.5f, -0.5f},  {-0.5f, -0.5f, 0.5f}, {0.5f, -0.5f, 0.5f},
                                         {0.5f, 0.5f, 0.5f},    {-0.5f, 0.5f, 0.5f}};
/// Five quads and one quad given as two triangles (faces 2 and 3); the last face is a quad.
const std::vector<std::vector<int>> kCubeFaces = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5}, {0, 5, 4},
                                                  {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
/// The fan of each face, as the loader must give it.
const std::vector<uint32_t> kCubeIndices = {0, 3, 2, 0, 2, 1, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                            1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7};

enum class CubeLayout {
  plain,    ///< float x y z; list uchar int vertex_indices (the fast path)
  rich,     ///< normals, colours, a list on vertices, an edge element, a face flag after the list
  doubles,  ///< an int before double x y z; list int int vertex_index
  offset,   ///< float confidence before float x y z; list uchar uint vertex_indices
};

std::string cube_ply(PlyFormat f, CubeLayout layout) {
  PlyWriter w(f);
  w.header("comment a cube").header("obj_info written by loaders_test");
  w.header("element vertex 8");
  switch (layout) {
    case CubeLayout::plain: w.header("property float x").header("property float y").header("property float z"); break;
    case CubeLayout::rich:
      w.header("property float32 x").header("property float32 y").header("property float32 z");
      w.header("property float nx").header("property float ny").header("property float nz");
      w.header("property uchar red").header("property list uchar float weights").header("property uint8 green");
      break;
    case CubeLayout::doubles:
      w.header("property int id").header("property double x").header("property double y").header("property double z");
      break;
    case CubeLayout::offset:
      w.header("property float confidence").header("property float x").header("property float y");
      w.header("property float z");
      break;
  }
  if (layout == CubeLayout::rich) w.header("element edge 2").header("property int v1").header("property int v2");
  w.header(cat("element face ", kCubeFaces.size()));
  switch (layout) {
    case CubeLayout::plain: w.header("property list uchar int vertex_indices"); break;
    case CubeLayout::rich: w.header("property list uint8 uint32 vertex_indices").header("property uchar flags"); break;
    case CubeLayout::doubles: w.header("property list int int vertex_index"); break;
    case CubeLayout::offset: w.header("property list uchar uint vertex_indices"); break;
  }
  for (size_t i = 0; i < kCubeVertices.size(); ++i) {
    const Vec3f& v = kCubeVertices[i];
    const char* type = layout == CubeLayout::doubles ? "double" : "float";
    if (layout == CubeLayout::doubles) w.put("int", double(i));
    if (layout == CubeLayout::offset) w.put("float", 0.5);
    w.put(type, v.x).put(type, v.y).put(type, v.z);
    if (layout == CubeLayout::rich) {
      const Vec3f& n = kCubeNormals[i];
      w.put("float", n.x).put("float", n.y).put("float", n.z).put("uchar", 200);
      w.put("uchar", double(i % 3));
      for (size_t k = 0; k < i % 3; ++k) w.put("float", 0.125 * double(k));
      w.put("uchar", 7);
    }
    w.end_item();
  }
  if (layout == CubeLayout::rich)
    for (int e = 0; e < 2; ++e) w.put("int", e).put("int", e + 1).end_item();
  for (const std::vector<int>& face : kCubeFaces) {
    const char* count = layout == CubeLayout::doubles ? "int" : "uchar";
    const char* index = layout == CubeLayout::doubles ? "int" : (layout == CubeLayout::plain ? "int" : "uint");
    w.put(count, double(face.size()));
    for (int v : face) w.put(index, v);
    if (layout == CubeLayout::rich) w.put("uchar", 1);
    w.end_item();
  }
  return w.str();
}

const char* name_of(PlyFormat f) {
  return f == PlyFormat::ascii ? "ascii" : f == PlyFormat::little_endian ? "little_endian" : "big_endian";
}

TEST(PlyLoader, AsciiLittleAndBigEndianCubesGiveIdenticalScenes) {
  for (CubeLayout layout : {CubeLayout::plain, CubeLayout::rich, CubeLayout::doubles, CubeLayout::offset})
    for (PlyFormat f : {PlyFormat::ascii, PlyFormat::little_endian, PlyFormat::big_endian}) {
      SCOPED_TRACE(cat("layout ", int(layout), ", ", name_of(f)));
      const Scene s = ply_scene("cube.ply", cube_ply(f, layout));
      ASSERT_EQ(s.meshes().size(), 1u);
      const TriangleMesh& m = s.meshes()[0];
      EXPECT_EQ(m.name, "cube");
      EXPECT_EQ(m.positions, kCubeVertices);
      EXPECT_EQ(m.indices, kCubeIndices);
      EXPECT_EQ(m.normals, layout == CubeLayout::rich ? kCubeNormals : std::vector<Vec3f>{});
      EXPECT_TRUE(m.uvs.empty());
      EXPECT_TRUE(m.face_materials.empty());
      EXPECT_EQ(s.triangle_count(), 12u);
    }
}

TEST(PlyLoader, NormalsNeedAllThreeComponents) {
  PlyWriter w(PlyFormat::ascii);
  w.header("element vertex 3").header("property float x").header("property float y").header("property float z");
  w.header("property float nx").header("property float ny");
  w.header("element face 1").header("property list uchar int vertex_indices");
  w.put("float", 0).put("float", 0).put("float", 0).put("float", 1).put("float", 0).end_item();
  w.put("float", 1).put("float", 0).put("float", 0).put("float", 1).put("float", 0).end_item();
  w.put("float", 0).put("float", 1).put("float", 0).put("float", 1).put("float", 0).end_item();
  w.put("uchar", 3).put("int", 0).put("int", 1).put("int", 2).end_item();
  const Scene s = ply_scene("two_normals.ply", w.str());
  EXPECT_TRUE(s.meshes()[0].normals.empty());
  EXPECT_EQ(s.meshes()[0].positions[1], Vec3f(1, 0, 0));
}

/// A one-triangle PLY with the given header lines after "format" and the given body.
std::string triangle_ply(PlyFormat f, const std::vector<Vec3f>& vertices, const std::vector<std::vector<int>>& faces,
                         const char* count_type = "uchar") {
  PlyWriter w(f);
  w.header(cat("element vertex ", vertices.size()));
  w.header("property float x").header("property float y").header("property float z");
  w.header(cat("element face ", faces.size())).header(cat("property list ", count_type, " int vertex_indices"));
  for (const Vec3f& v : vertices) w.put("float", v.x).put("float", v.y).put("float", v.z).end_item();
  for (const std::vector<int>& face : faces) {
    w.put(count_type, double(face.size()));
    for (int i : face) w.put("int", i);
    w.end_item();
  }
  return w.str();
}

TEST(PlyLoader, BadHeadersThrowTheExactError) {
  const std::string tail = "element vertex 0\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  EXPECT_EQ(ply_error("magic.ply", "plx\nformat ascii 1.0\n" + tail),
            path_of("magic.ply") + ": line 1: not a PLY file (the first line is not 'ply')");
  EXPECT_EQ(ply_error("empty.ply", ""), path_of("empty.ply") + ": line 1: not a PLY file (the first line is not 'ply')");
  EXPECT_EQ(ply_error("format.ply", "ply\nformat binary_middle_endian 1.0\n" + tail),
            path_of("format.ply") +
                ": line 2: unknown format 'binary_middle_endian' (ascii, binary_little_endian, binary_big_endian)");
  EXPECT_EQ(ply_error("version.ply", "ply\nformat ascii 2.0\n" + tail),
            path_of("version.ply") + ": line 2: unsupported PLY version '2.0' (1.0)");
  EXPECT_EQ(ply_error("noformat.ply", "ply\n" + tail), path_of("noformat.ply") + ": line 6: no 'format' line before 'end_header'");
  EXPECT_EQ(ply_error("type.ply", "ply\nformat ascii 1.0\nelement vertex 0\nproperty float128 x\nend_header\n"),
            path_of("type.ply") + ": line 4: unknown property type 'float128'");
  EXPECT_EQ(ply_error("count_type.ply", "ply\nformat ascii 1.0\nelement face 0\nproperty list float int vertex_indices\n"
                                        "end_header\n"),
            path_of("count_type.ply") + ": line 4: list count type 'float' is not an integer type");
  EXPECT_EQ(ply_error("no_y.ply", "ply\nformat ascii 1.0\ncomment no y\nelement vertex 0\nproperty float x\n"
                                  "property float z\nend_header\n"),
            path_of("no_y.ply") + ": line 4: element 'vertex' has no property 'y'");
  EXPECT_EQ(ply_error("no_vertex.ply", "ply\nformat ascii 1.0\nend_header\n"),
            path_of("no_vertex.ply") + ": the header declares no 'vertex' element");
  EXPECT_EQ(ply_error("no_end.ply", "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
                                    "property float z\n"),
            path_of("no_end.ply") + ": line 6: end of file before 'end_header'");
  EXPECT_EQ(ply_error("keyword.ply", "ply\nformat ascii 1.0\nelements vertex 0\nend_header\n"),
            path_of("keyword.ply") + ": line 3: unexpected 'elements' in the header");
  EXPECT_EQ(ply_error("element_count.ply", "ply\nformat ascii 1.0\nelement vertex many\nend_header\n"),
            path_of("element_count.ply") + ": line 3: 'many' is not an element count");
  EXPECT_EQ(ply_error("no_list.ply", "ply\nformat ascii 1.0\n" + tail.substr(0, tail.size() - 11) +
                                         "element face 0\nproperty int vertex_indices\nend_header\n"),
            path_of("no_list.ply") + ": line 7: element 'face' has no list property 'vertex_indices'");
  EXPECT_EQ(error_of([] {
              Scene s;
              load_ply(path_of("absent.ply"), s);
            }),
            path_of("absent.ply") + ": cannot open: No such file or directory");
}

TEST(PlyLoader, CountsBeyondTheFileSizeAreRefusedBeforeAllocating) {
  // 4e9 vertices of 12 bytes would be 48 GB: refused from the header alone.
  std::string ply = triangle_ply(PlyFormat::little_endian, {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}});
  const size_t at = ply.find("element vertex 3");
  ply.replace(at, 16, "element vertex 4000000000");
  const size_t after_header = ply.size() - (ply.find("end_header\n") + 11);
  EXPECT_EQ(ply_error("huge.ply", ply), cat(path_of("huge.ply"), ": element 'vertex' declares 4000000000 items but ",
                                            "the file has only ", after_header, " bytes after the header"));
  std::string ascii = triangle_ply(PlyFormat::ascii, {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}});
  ascii.replace(ascii.find("element face 1"), 14, "element face 18446744073709551615");
  const size_t ascii_after = ascii.size() - (ascii.find("end_header\n") + 11);
  EXPECT_EQ(ply_error("huge_faces.ply", ascii),
            cat(path_of("huge_faces.ply"), ": element 'face' declares 18446744073709551615 items but the file has only ",
                ascii_after, " bytes after the header"));
}

TEST(PlyLoader, TruncatedDataNamesTheItemAndWhereTheFileEnds) {
  std::string binary = cube_ply(PlyFormat::little_endian, CubeLayout::plain);
  binary.resize(binary.size() - 2);  // the last face, a quad, loses half an index
  EXPECT_EQ(ply_error("truncated.ply", binary),
            cat(path_of("truncated.ply"), ": truncated: face 6 ends past the end of the file at byte offset ",
                binary.size()));
  std::string big = cube_ply(PlyFormat::big_endian, CubeLayout::rich);
  big.resize(big.size() - 2);  // the face's flag byte and one index byte
  EXPECT_EQ(ply_error("truncated_be.ply", big),
            cat(path_of("truncated_be.ply"), ": truncated: face 6 ends past the end of the file at byte offset ",
                big.size()));
  std::string ascii = cube_ply(PlyFormat::ascii, CubeLayout::plain);
  ascii.resize(ascii.size() - 4);  // the last face "4 3 0 4 7\n" (line 26) loses "4 7\n"
  EXPECT_EQ(ply_error("truncated_ascii.ply", ascii),
            path_of("truncated_ascii.ply") + ": truncated: face 6 ends past the end of the file at line 26");
}

TEST(PlyLoader, BadDataThrowsTheExactError) {
  const std::vector<Vec3f> tri = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  for (PlyFormat f : {PlyFormat::ascii, PlyFormat::little_endian, PlyFormat::big_endian}) {
    SCOPED_TRACE(name_of(f));
    EXPECT_EQ(ply_error("range.ply", triangle_ply(f, tri, {{0, 1, 2}, {2, 1, 0}, {0, 1, 99}})),
              path_of("range.ply") + ": face 2 uses vertex 99 of 3");
    EXPECT_EQ(ply_error("negative.ply", triangle_ply(f, tri, {{0, 1, 2, -1}})),
              path_of("negative.ply") + ": face 0 uses vertex -1 of 3");
    // A pentagon after the 2-corner face keeps the file above the 3-index minimum that the size
    // check assumes, so the face itself is reported.
    EXPECT_EQ(ply_error("two.ply", triangle_ply(f, tri, {{0, 1, 2}, {0, 1}, {0, 1, 2, 0, 1}})),
              path_of("two.ply") + ": face 1 has 2 vertices (a face needs at least 3)");
    EXPECT_EQ(ply_error("two_int.ply", triangle_ply(f, tri, {{0, 1}, {0, 1, 2, 0, 1}}, "int")),
              path_of("two_int.ply") + ": face 0 has 2 vertices (a face needs at least 3)");
    EXPECT_EQ(ply_error("nan.ply", triangle_ply(f, {{0, 0, 0}, {1, 0, 0}, {0, NAN, 0}}, {{0, 1, 2}})),
              path_of("nan.ply") + ": vertex 2 has a non-finite coordinate");
    EXPECT_EQ(ply_error("inf.ply", triangle_ply(f, {{0, 0, 0}, {1, -INFINITY, 0}, {0, 1, 0}}, {{0, 1, 2}})),
              path_of("inf.ply") + ": vertex 1 has a non-finite coordinate");
  }
  std::string ascii = triangle_ply(PlyFormat::ascii, tri, {{0, 1, 2}});
  ascii.replace(ascii.find("\n1 0 0\n") + 1, 1, "abc");
  EXPECT_EQ(ply_error("abc.ply", ascii), path_of("abc.ply") + ": line 11: 'abc' is not a number");
  std::string fraction = triangle_ply(PlyFormat::ascii, tri, {{0, 1, 2}});
  fraction.replace(fraction.rfind("2\n"), 1, "1.5");
  EXPECT_EQ(ply_error("fraction.ply", fraction), path_of("fraction.ply") + ": line 13: '1.5' is not an integer");
  std::string overflow = triangle_ply(PlyFormat::ascii, tri, {{0, 1, 2}});
  overflow.replace(overflow.find("\n1 0 0\n") + 1, 1, "1e999");
  EXPECT_EQ(ply_error("overflow.ply", overflow), path_of("overflow.ply") + ": vertex 1 has a non-finite coordinate");
}

TEST(PlyLoader, CoordinatesOutsideTheRangeAreRefused) {
  for (PlyFormat f : {PlyFormat::ascii, PlyFormat::little_endian, PlyFormat::big_endian}) {
    SCOPED_TRACE(name_of(f));
    EXPECT_EQ(ply_error("far.ply", triangle_ply(f, {{0, 0, 0}, {1e19f, 0, 0}, {0, 1, 0}}, {{0, 1, 2}})),
              path_of("far.ply") + ": vertex 1 (1e+19, 0, 0) is outside the supported coordinate range |x| <= "
                                   "1073741824 (2^30)");
    EXPECT_EQ(ply_error("edge.ply", triangle_ply(f, {{0, 0, 0}, {0x1p30f, 0, 0}, {0, -0x1p30f, 0}}, {{0, 1, 2}})),
              "no error");
  }
}

TEST(PlyLoader, PolygonsAreFannedAndOtherElementsSkipped) {
  PlyWriter w(PlyFormat::big_endian);
  w.header("element material 2").header("property list uchar uchar name").header("property float shine");
  w.header("element vertex 5").header("property double x").header("property double y").header("property double z");
  w.header("element face 1").header("property list ushort uint vertex_indices");
  for (int m = 0; m < 2; ++m) w.put("uchar", 3).put("uchar", 'a').put("uchar", 'b').put("uchar", 'c').put("float", 1);
  for (int i = 0; i < 5; ++i) w.put("double", std::cos(0.4 * kPi * i)).put("double", std::sin(0.4 * kPi * i)).put("double", 2);
  w.put("ushort", 5);
  for (int i = 0; i < 5; ++i) w.put("uint", i);
  const Scene s = ply_scene("pentagon.ply", w.str());
  EXPECT_EQ(s.meshes()[0].indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3, 0, 3, 4}));
  EXPECT_FLOAT_EQ(s.meshes()[0].positions[1].x, float(std::cos(0.4 * kPi)));
}

// --- load_scene --------------------------------------------------------------------------------

TEST(LoadScene, DefaultNameGivesTheEmbeddedScene) {
  const Scene s = load_scene("default");
  EXPECT_EQ(s.triangle_count(), make_default_scene().triangle_count());
  EXPECT_GE(s.triangle_count(), 50000u);
}

TEST(LoadScene, ExtensionPicksTheLoaderIgnoringCase) {
  EXPECT_EQ(load_scene(write_file("CUBE.PLY", cube_ply(PlyFormat::ascii, CubeLayout::plain))).triangle_count(), 12u);
  EXPECT_EQ(load_scene(write_file("Quad.Obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n")).triangle_count(), 2u);
}

TEST(LoadScene, UnknownFormatsAreRefused) {
  EXPECT_EQ(error_of([] { load_scene("model.stl"); }), "model.stl: unknown scene format '.stl' (.obj, .ply, .json)");
  EXPECT_EQ(error_of([] { load_scene("model"); }), "model: unknown scene format '' (.obj, .ply, .json)");
  EXPECT_EQ(error_of([] { load_scene("scenes.d/model"); }), "scenes.d/model: unknown scene format '' (.obj, .ply, .json)");
  EXPECT_EQ(error_of([] { load_scene(path_of("absent.ply")); }),
            path_of("absent.ply") + ": cannot open: No such file or directory");
}

TEST(LoadScene, FileWithoutTrianglesIsAnError) {
  const std::string path = write_file("points.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                                                    "property float y\nproperty float z\nend_header\n0 0 0\n");
  EXPECT_EQ(error_of([&] { load_scene(path); }), path + ": the file has no triangles");
}

TEST(LoadScene, LightsArePlacedFromTheBoundsWhenTheFileHasNone) {
  const Scene s = load_scene(write_file("lit.ply", cube_ply(PlyFormat::little_endian, CubeLayout::plain)));
  ASSERT_EQ(s.point_lights().size(), 1u);
  ASSERT_EQ(s.directional_lights().size(), 1u);
  EXPECT_FALSE(s.camera().has_value());
  const Box3f b = s.bounds();
  const float r = 0.5f * length(b.extent());
  const PointLight& key = s.point_lights()[0];
  const Vec3f offset = Vec3f(0.5f, 1.5f, 2.0f) * r;
  EXPECT_EQ(key.position, b.center() + offset);
  EXPECT_GT(key.position.y, b.hi.y);  // above
  EXPECT_GT(key.position.z, b.hi.z);  // in front (+Z)
  EXPECT_NEAR(key.intensity.x / dot(offset, offset), 0.8f, 1e-6f);  // irradiance 0.8 at the centre
  const DirectionalLight& fill = s.directional_lights()[0];
  EXPECT_NEAR(length(fill.direction), 1.0f, 1e-6f);
  EXPECT_LT(fill.direction.y, 0.0f);  // from above
  EXPECT_EQ(fill.irradiance, Vec3f(0.3f));
}

// --- the real models ---------------------------------------------------------------------------

struct RealModel {
  const char* file;
  uint32_t triangles;  ///< from ../shared/scenes/README.md
};

class RealModels : public testing::TestWithParam<RealModel> {};

TEST_P(RealModels, TriangleCountMatchesTheReadme) {
  const fs::path dir = RP_SHARED_SCENES;
  if (!fs::is_directory(dir)) GTEST_SKIP() << dir.string() << " is absent: real-model loader checks not run";
  const RealModel& model = GetParam();
  const std::string path = (dir / model.file).string();
  const auto start = std::chrono::steady_clock::now();
  const Scene s = load_scene(path);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  std::printf("[ loaded   ] %s in %.1f ms\n", model.file, ms);
  RecordProperty("load_ms", std::to_string(ms));
  EXPECT_EQ(s.triangle_count(), model.triangles);
  EXPECT_EQ(s.point_lights().size(), 1u);
  EXPECT_FALSE(s.bounds().empty());

  size_t vertices = 0;
  for (const TriangleMesh& m : s.meshes()) vertices += m.positions.size();
  const std::string name = model.file;
  if (name == "CornellBox-Original.obj") {
    ASSERT_EQ(s.materials().size(), 9u);  // default + 8 from the MTL
    const auto light = std::find_if(s.materials().begin(), s.materials().end(),
                                    [](const Material& m) { return m.name == "light"; });
    ASSERT_NE(light, s.materials().end());
    EXPECT_EQ(light->emission, Vec3f(17, 12, 4));
  } else if (name == "suzanne.obj") {
    EXPECT_EQ(s.meshes()[0].normals.size(), s.meshes()[0].positions.size());
  } else if (name == "spot.obj") {
    EXPECT_EQ(s.meshes()[0].uvs.size(), s.meshes()[0].positions.size());
  } else if (name == "bunny.obj") {
    EXPECT_EQ(vertices, 35947u - 1113u);  // the unreferenced vertices are dropped
  } else if (name == "buddha.ply") {
    EXPECT_EQ(vertices, 32328u);
  } else if (name == "sponza.obj") {
    // 68 'g' lines: 34 named groups with faces, each followed by a bare 'g' before its vertices.
    EXPECT_EQ(s.meshes().size(), 34u);
    EXPECT_EQ(s.materials().size(), 1u);
    for (const TriangleMesh& m : s.meshes()) {
      EXPECT_EQ(m.normals.size(), m.positions.size());
      EXPECT_EQ(m.uvs.size(), m.positions.size());
    }
    EXPECT_EQ(s.degenerate_triangle_count(), 1u);
  } else if (name == "dragon.ply") {
    EXPECT_EQ(vertices, 437645u);
  }
}

INSTANTIATE_TEST_SUITE_P(Readme, RealModels,
                         testing::Values(RealModel{"CornellBox-Original.obj", 36}, RealModel{"suzanne.obj", 968},
                                         RealModel{"teapot.obj", 6320}, RealModel{"spot.obj", 5856},
                                         RealModel{"bunny.obj", 69451}, RealModel{"buddha.ply", 67240},
                                         RealModel{"sponza.obj", 66454}, RealModel{"dragon.ply", 871414}),
                         [](const testing::TestParamInfo<RealModel>& info) {
                           std::string n = info.param.file;
                           n = n.substr(0, n.find('.'));
                           std::replace(n.begin(), n.end(), '-', '_');
                           return n;
                         });

}  // namespace
}  // namespace rp
