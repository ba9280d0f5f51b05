/// The glTF 2.0 loader (engine/loaders/gltf.cpp) on files the tests write with tinygltf's
/// writer (tests/support/gltf_files.h): the node hierarchy composed in glTF's order (against
/// the tests' own composition), a mesh placed by several nodes stored once with an instance
/// each, every index type, strips and fans, normals, materials, cameras and lights, the three
/// forms of a file (data URIs, an external .bin, .glb) giving one scene, and the exact one-line
/// message of every hostile file: truncated GLB, bad accessor offsets and strides, indices out
/// of range, node cycles, absurd counts, buffers naming a device, a directory or nothing,
/// sparse accessors, Draco, non-affine matrices, deep JSON.

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>
#include <vector>

#include "engine/error.h"
#include "engine/loaders/load.h"
#include "scratch.h"
#include "tests/support/gltf_files.h"

namespace rp {
namespace {

namespace fs = std::filesystem;
using test::GltfBuilder;
using test::GltfForm;
using test::scratch;

/// `model` written as `name` in `form` in the scratch folder; its path.
std::string written(const tinygltf::Model& model, const std::string& name, GltfForm form,
                    const std::function<void(nlohmann::json&)>& patch = {}) {
  const fs::path path = scratch() / name;
  fs::create_directories(path.parent_path());
  test::write_gltf(model, path.string(), form, patch);
  return path.string();
}

/// what() of load_scene(path)'s rp::Error with the scratch folder's path removed, or "no error".
std::string error_loading(const std::string& path) {
  std::string s = test::error_of([&] { load_scene(path); });
  const std::string dir = scratch().string() + "/";
  for (size_t at = s.find(dir); at != std::string::npos; at = s.find(dir)) s.erase(at, dir.size());
  return s;
}

void expect_near(const Vec3d& a, const Vec3d& b, double tolerance, const std::string& what) {
  EXPECT_LE(length(a - b), tolerance) << what << ": (" << a.x << ", " << a.y << ", " << a.z << ") vs (" << b.x << ", "
                                      << b.y << ", " << b.z << ")";
}

/// The scene's triangles in world coordinates: world meshes as they are, instanced meshes
/// mapped by each instance in double.
std::vector<std::array<Vec3d, 3>> world_triangles(const Scene& s) {
  std::vector<std::array<Vec3d, 3>> out;
  const auto add = [&](const TriangleMesh& m, const Affine3d& a) {
    for (uint32_t t = 0; t < m.triangle_count(); ++t)
      out.push_back({a.point(Vec3d(m.vertex(t, 0))), a.point(Vec3d(m.vertex(t, 1))), a.point(Vec3d(m.vertex(t, 2)))});
  };
  for (size_t i = 0; i < s.meshes().size(); ++i)
    if (!s.is_instanced(i)) add(s.meshes()[i], Affine3d{});
  for (const Instance& in : s.instances()) add(s.meshes()[in.mesh], Affine3d(in.object_to_world));
  return out;
}

/// Every triangle of `want` in `got` (same corners in the same order, within `tolerance`), and
/// as many.
void expect_same_triangles(const std::vector<std::array<Vec3d, 3>>& got, const std::vector<std::array<Vec3d, 3>>& want,
                           double tolerance) {
  ASSERT_EQ(got.size(), want.size());
  std::vector<bool> used(got.size(), false);
  for (size_t w = 0; w < want.size(); ++w) {
    bool found = false;
    for (size_t g = 0; g < got.size() && !found; ++g) {
      if (used[g]) continue;
      bool same = true;
      for (int k = 0; k < 3; ++k) same = same && length(got[g][size_t(k)] - want[w][size_t(k)]) <= tolerance;
      if (same) used[g] = found = true;
    }
    EXPECT_TRUE(found) << "triangle " << w << " of the tests' composition is not in the scene";
  }
}

TEST(GltfLoader, TheHierarchyIsComposedInGltfOrderAndAMeshSeveralNodesPlaceIsStoredOnce) {
  const test::HierarchyGltf h = test::hierarchy_gltf();
  const Scene s = load_scene(written(h.model, "hierarchy.gltf", GltfForm::embedded));
  // "pair" (2 triangles) stored once and placed by three instances; "mixed", "strip", "fan"
  // placed once each, baked into world meshes.
  ASSERT_EQ(s.meshes().size(), 4u);
  EXPECT_TRUE(s.is_instanced(0));
  EXPECT_EQ(s.meshes()[0].triangle_count(), 2u);
  EXPECT_EQ(s.instances().size(), size_t(h.pair_mesh_placements));
  EXPECT_EQ(s.instanced_triangle_count(), 6u);
  EXPECT_EQ(s.meshes()[1].triangle_count(), 4u + 2u);  // a tetrahedron and two loose triangles
  EXPECT_EQ(s.meshes()[2].triangle_count(), 4u);       // a strip of six vertices
  EXPECT_EQ(s.meshes()[3].triangle_count(), 3u);       // a fan of five
  expect_same_triangles(world_triangles(s), h.world_triangles, 2e-6);
}

TEST(GltfLoader, TheThreeFormsOfAFileGiveTheSameScene) {
  const test::HierarchyGltf h = test::hierarchy_gltf();
  const Scene a = load_scene(written(h.model, "forms/data.gltf", GltfForm::embedded));
  const Scene b = load_scene(written(h.model, "forms/external.gltf", GltfForm::external));
  const Scene c = load_scene(written(h.model, "forms/binary.glb", GltfForm::binary));
  EXPECT_TRUE(fs::exists(scratch() / "forms/external.bin"));
  for (const Scene* s : {&b, &c}) {
    ASSERT_EQ(s->meshes().size(), a.meshes().size());
    for (size_t m = 0; m < a.meshes().size(); ++m) {
      EXPECT_EQ(s->meshes()[m].positions, a.meshes()[m].positions);
      EXPECT_EQ(s->meshes()[m].indices, a.meshes()[m].indices);
      EXPECT_EQ(s->meshes()[m].normals, a.meshes()[m].normals);
    }
    ASSERT_EQ(s->instances().size(), a.instances().size());
    for (size_t i = 0; i < a.instances().size(); ++i)
      EXPECT_TRUE(s->instances()[i].object_to_world == a.instances()[i].object_to_world);
  }
}

TEST(GltfLoader, NormalsMaterialsAndPrimitiveMaterialsAreKept) {
  const test::HierarchyGltf h = test::hierarchy_gltf();
  const Scene s = load_scene(written(h.model, "materials.gltf", GltfForm::embedded));
  // Materials: the default, then red and green as first used.
  ASSERT_EQ(s.materials().size(), 3u);
  const Material& red = s.materials()[s.meshes()[0].material];
  EXPECT_EQ(red.name, "red");
  EXPECT_EQ(red.diffuse, Vec3f(0.8f, 0.1f, 0.1f));
  // "mixed": the tetrahedron's triangles green (with its emission), the loose ones the default.
  const TriangleMesh& mixed = s.meshes()[1];
  ASSERT_EQ(mixed.face_materials.size(), 6u);
  EXPECT_EQ(s.materials()[mixed.face_materials[0]].name, "green");
  EXPECT_EQ(s.materials()[mixed.face_materials[0]].emission, Vec3f(0.1f, 0.2f, 0.3f));
  EXPECT_EQ(mixed.face_materials[5], 0u);
  // "pair" keeps its normals in its own coordinates (the instances map them when shading).
  ASSERT_EQ(s.meshes()[0].normals.size(), 4u);
  EXPECT_EQ(s.meshes()[0].normals[0], Vec3f(0, 0, 1));
  EXPECT_TRUE(s.meshes()[1].normals.empty());
}

TEST(GltfLoader, ABakedMeshsNormalsFollowTheInverseTranspose) {
  // One quad placed once by a node scaling x by 4 and turning 90 degrees about z: a normal
  // (1, 0, 1) / sqrt(2) becomes (0, 1/4, 1) normalised, by the inverse transpose.
  GltfBuilder b;
  const float r = float(1.0 / std::sqrt(2.0));
  const int mesh = b.mesh({GltfBuilder::primitive(b.vectors({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}), -1,
                                                  b.vectors(std::vector<Vec3f>(3, Vec3f(r, 0, r))))});
  b.scene({b.node(mesh, {}, {0, 0, std::sin(kPi / 4), std::cos(kPi / 4)}, {4, 1, 1})});
  const Scene s = load_scene(written(b.model, "normals.gltf", GltfForm::embedded));
  ASSERT_EQ(s.meshes().size(), 1u);
  EXPECT_FALSE(s.is_instanced(0));
  expect_near(Vec3d(s.meshes()[0].normals[0]), normalize(Vec3d(0, 0.25, 1)), 1e-6, "normal");
  expect_near(Vec3d(s.meshes()[0].positions[1]), {0, 4, 0}, 1e-6, "corner");
}

TEST(GltfLoader, TheFirstPerspectiveCameraAndThePunctualLightsArePlaced) {
  const GltfBuilder b = test::camera_and_lights_gltf();
  const Scene s = load_scene(written(b.model, "camera.glb", GltfForm::binary));
  ASSERT_TRUE(s.camera().has_value());
  EXPECT_EQ(s.camera()->eye, Vec3f(0, 0, 5));
  EXPECT_EQ(s.camera()->look_at, Vec3f(0, 0, 4));
  EXPECT_EQ(s.camera()->up, Vec3f(0, 1, 0));
  EXPECT_FLOAT_EQ(s.camera()->vfov_degrees, 45.0f);
  ASSERT_EQ(s.point_lights().size(), 2u);  // the point light and the spot, as a point light
  EXPECT_EQ(s.point_lights()[0].position, Vec3f(1, 2, 3));
  EXPECT_EQ(s.point_lights()[0].intensity, Vec3f(20.0f, 10.0f, 5.0f));
  EXPECT_EQ(s.point_lights()[1].position, Vec3f(0, 4, 0));
  ASSERT_EQ(s.directional_lights().size(), 1u);
  expect_near(Vec3d(s.directional_lights()[0].direction), {0, -1, 0}, 1e-6, "sun");
  EXPECT_EQ(s.directional_lights()[0].irradiance, Vec3f(3.0f));
  EXPECT_EQ(s.up_axis(), 1);  // glTF is Y up
}

TEST(GltfLoader, PointsAndLinesAreSkippedAndTheFileStillLoads) {
  GltfBuilder b;
  const int pos = b.vectors({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
  b.scene({b.node(b.mesh({GltfBuilder::primitive(pos, -1, -1, -1, TINYGLTF_MODE_LINE),
                          GltfBuilder::primitive(pos, -1, -1, -1, TINYGLTF_MODE_POINTS),
                          GltfBuilder::primitive(pos)}))});
  const Scene s = load_scene(written(b.model, "lines.gltf", GltfForm::embedded));
  EXPECT_EQ(s.triangle_count(), 1u);
  // Only lines: no triangles at all.
  GltfBuilder only;
  only.scene({only.node(only.mesh({GltfBuilder::primitive(only.vectors({{0, 0, 0}, {1, 0, 0}}), -1, -1, -1, TINYGLTF_MODE_LINE)}))});
  EXPECT_EQ(error_loading(written(only.model, "only-lines.gltf", GltfForm::embedded)), "only-lines.gltf: the file has no triangles");
}

// ---- hostile files: one line each, naming the file and the JSON path ----

TEST(GltfErrors, EveryHostileFileIsRefusedWithOneLineNamingTheFileAndTheJsonPath) {
  // The cases of tests/support/gltf_files.h (the fuzz corpus holds the same files), each with
  // its exact message.
  const std::string up = test::to_root();
  const std::map<std::string, std::string> want = {
      {"bad-offset.gltf",
       "$.accessors[0]: 3 elements of 12 bytes, 12 apart from byte 8, do not fit in bufferViews[0]'s 36 bytes"},
      {"bad-stride.gltf", "$.bufferViews[0].byteStride: 8 is outside [12, 252] for 12-byte elements"},
      {"bad-count.gltf",
       "$.accessors[0]: 4000000000 elements of 12 bytes, 12 apart from byte 0, do not fit in bufferViews[0]'s 36 "
       "bytes"},
      {"bad-view-length.gltf", "$.bufferViews[0]: 1000 bytes from byte 0 do not fit in buffer 0's 42 bytes"},
      {"bad-index.gltf", "$.meshes[0].primitives[0].indices: index 3 (element 1) is out of range (3 vertices)"},
      {"bad-cycle.gltf", "$.nodes[1].children[0]: node 0 is its own ancestor (a cycle)"},
      {"bad-two-parents.gltf", "$.nodes[2].children[0]: node 0 is reached twice (a node may have one parent only)"},
      {"bad-missing-buffer.gltf",
       "$.buffers[0].uri: \"missing.bin\": hostile/missing.bin: cannot open: No such file or directory"},
      {"bad-device-uri.gltf", "$.buffers[0].uri: \"" + up.substr(0, 32) + "...\": hostile/" + up +
                                  "dev/zero: cannot read: not a regular file (a character device)"},
      {"bad-directory-uri.gltf",
       "$.buffers[0].uri: \"folder.bin\": hostile/folder.bin: cannot read: not a regular file (a directory)"},
      {"bad-sparse.gltf", "$.accessors[0].sparse: sparse accessors are not supported"},
      {"bad-draco.gltf",
       "$.meshes[0].primitives[0].extensions.KHR_draco_mesh_compression: Draco-compressed primitives are not "
       "supported"},
      {"bad-required-draco.gltf",
       "$.extensionsRequired[0]: \"KHR_draco_mesh_compression\" is not supported (its geometry cannot be read without "
       "it)"},
      {"bad-matrix.gltf", "$.nodes[0].matrix: not an affine transform (its last row is not 0 0 0 1)"},
      {"bad-far.gltf",
       "$.nodes[0]: mesh 'mesh 0': vertex 0 (2e+09, 0, 0) is outside the supported coordinate range "
       "|x| <= 1073741824 (2^30)"},
      {"bad-quaternion.gltf", "$.nodes[0].rotation: a zero quaternion is no rotation"},
      {"bad-no-scene.gltf", "$.scenes: the file has no scene"},
      {"bad-missing-node.gltf", "$.nodes[0].children[0]: 7 names no node (1 nodes)"},
      {"bad-light-type.gltf",
       "$.extensions.KHR_lights_punctual.lights[0].type: \"area\" is not a KHR_lights_punctual type (directional, "
       "point, "
       "spot)"}};
  fs::create_directories(scratch() / "hostile" / "folder.bin");
  size_t checked = 0;
  for (const test::GltfCase& c : test::hostile_gltf_cases()) {
    SCOPED_TRACE(c.name);
    const std::string message = error_loading(test::write_case(c, (scratch() / "hostile").string()));
    if (c.name == "bad-truncated.glb") {
      test::GltfCase whole = c;
      whole.keep = 0;
      whole.name = "whole.glb";
      const uintmax_t size = fs::file_size(test::write_case(whole, (scratch() / "hostile").string()));
      EXPECT_EQ(message, "hostile/bad-truncated.glb: truncated GLB: the header says " + std::to_string(size) +
                             " bytes, the file has 90");
    } else if (c.name == "bad-deep.gltf") {
      EXPECT_EQ(message.substr(0, 25), "hostile/bad-deep.gltf: li") << message;
      EXPECT_NE(message.find("nesting deeper than 64 levels"), std::string::npos) << message;
    } else {
      ASSERT_TRUE(want.count(c.name)) << "no message for this case";
      EXPECT_EQ(message, "hostile/" + c.name + ": " + want.at(c.name));
    }
    ++checked;
  }
  EXPECT_EQ(checked, want.size() + 2);
}

TEST(GltfErrors, AMalformedGlbHeaderIsRefused) {
  const std::string path = written(test::one_triangle().model, "short.glb", GltfForm::binary);
  fs::resize_file(path, 12);
  EXPECT_EQ(error_loading(path), "short.glb: truncated GLB: 12 bytes, its headers need 20");
  std::ofstream(path, std::ios::binary | std::ios::trunc) << "glTF" << std::string(16, '\x01');
  EXPECT_EQ(error_loading(path), "short.glb: GLB version 16843009 (2 is read)");
}

/// Every chunk of a GLB must lie inside the file (tinygltf 2.7 checks the BIN chunk's length
/// without its 8-byte header and read past the end of the file, a SIGSEGV at a page's end): a
/// BIN chunk claiming 8 bytes or 1 byte more than follow, a BIN header cut short, a second
/// chunk that is not BIN and a third chunk claiming more than follow are each refused with one
/// line; the file as written, and with a third chunk that fits, loads. The GLB header's total
/// length is kept equal to the file's size in each, so only the chunk is wrong.
TEST(GltfErrors, EveryGlbChunkMustLieInsideTheFile) {
  const std::string path = written(test::one_triangle().model, "chunks.glb", GltfForm::binary);
  std::string good;
  {
    std::ifstream in(path, std::ios::binary);
    good.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  const auto u32 = [](const std::string& b, size_t at) {
    uint32_t v;
    std::memcpy(&v, b.data() + at, 4);
    return v;
  };
  const auto put32 = [](std::string& b, size_t at, uint32_t v) { std::memcpy(b.data() + at, &v, 4); };
  const size_t bin_at = 20 + u32(good, 12);
  const uint32_t bin_bytes = u32(good, bin_at);
  ASSERT_EQ(bin_at + 8 + bin_bytes, good.size());
  ASSERT_EQ(good.substr(bin_at + 4, 4), std::string("BIN\0", 4));
  // `bytes` as the file, its header's total length set to its size.
  const auto error_with = [&](std::string bytes) {
    put32(bytes, 8, uint32_t(bytes.size()));
    std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
    return error_loading(path);
  };
  EXPECT_EQ(error_with(good), "no error");
  for (uint32_t more : {8u, 1u}) {
    std::string b = good;
    put32(b, bin_at, bin_bytes + more);
    EXPECT_EQ(error_with(b), "chunks.glb: truncated GLB: its BIN chunk says " + std::to_string(bin_bytes + more) +
                                 " bytes, " + std::to_string(bin_bytes) + " follow");
  }
  EXPECT_EQ(error_with(good.substr(0, bin_at + 4)),
            "chunks.glb: truncated GLB: the chunk at byte " + std::to_string(bin_at) + " has 4 of its 8 header bytes");
  std::string other = good;
  other.replace(bin_at + 4, 4, "EXT\x01");
  EXPECT_EQ(error_with(other), "chunks.glb: GLB whose second chunk is of type \"EXT?\", not BIN");
  std::string third = good;
  third += std::string("\x10\0\0\0EXT\0", 8) + "abcd";  // claims 16 bytes, 4 follow
  EXPECT_EQ(error_with(third),
            "chunks.glb: truncated GLB: its chunk at byte " + std::to_string(good.size()) + " says 16 bytes, 4 follow");
  put32(third, good.size(), 4);
  EXPECT_EQ(error_with(third), "no error");
}

}  // namespace
}  // namespace rp
