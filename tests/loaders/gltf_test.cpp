/// The glTF 2.0 loader (io/loaders/gltf.cpp) on files the tests write with tinygltf's
/// writer (tests/support/gltf_files.h): the node hierarchy composed in glTF's order (against
/// the tests' own composition), a mesh placed by several nodes stored once with an instance
/// each, every index type, strips and fans, normals, materials, cameras and lights, the three
/// forms of a file (data URIs, an external .bin, .glb) giving one scene, and the exact one-line
/// message of every hostile file: truncated GLB, bad accessor offsets and strides, indices out
/// of range, node cycles, absurd counts, buffers naming a device, a directory or nothing,
/// sparse accessors, Draco, non-affine matrices, deep JSON, buffer URIs leading out of the
/// glTF's folder, values of the wrong type or range (which tinygltf would turn into defaults),
/// rotations that are not unit quaternions, float and out-of-range indices, and what tinygltf
/// refused without a JSON path; and repeated warnings printed once with a count.

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>
#include <vector>

#include "base/error.h"
#include "gltf_scratch.h"
#include "io/loaders/load.h"
#include "scratch.h"
#include "tests/support/gltf_files.h"

namespace rp {
namespace {

namespace fs = std::filesystem;
using test::error_loading;
using test::GltfBuilder;
using test::GltfForm;
using test::scratch;
using test::written;

void expect_near(const Vec3d& a, const Vec3d& b, double tolerance, const std::string& what) {
  EXPECT_LE(length(a - b), tolerance) << what << ": (" << a.x << ", " << a.y << ", " << a.z << ") vs (" << b.x << ", "
                                      << b.y << ", " << b.z << ")";
}

/// The scene's triangles in world coordinates: world meshes as they are, instanced meshes
/// mapped by each instance in double.
std::vector<std::array<Vec3d, 3>> world_triangles(const Scene& s) {
  std::vector<std::array<Vec3d, 3>> out;
  const auto add = [&](const MeshView& m, const Affine3d& a) {
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
      const TriangleMesh x = to_triangle_mesh(s->meshes()[m]), y = to_triangle_mesh(a.meshes()[m]);
      EXPECT_EQ(x.positions, y.positions);
      EXPECT_EQ(x.indices, y.indices);
      EXPECT_EQ(x.normals, y.normals);
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
  const TriangleMesh mixed = to_triangle_mesh(s.meshes()[1]);
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

/// A file of many nodes whose objects tinygltf can hold within the memory budget loads, each
/// node placing its instance: 20,000 nodes in 0.8 MB of JSON, about 9 MiB of tinygltf::Node
/// and 9 MiB of JSON DOM, under the 256 MiB floor.
TEST(GltfLoader, AFileOfManyNodesWithinTheMemoryBudgetLoads) {
  nlohmann::json doc;
  {
    std::ifstream in(written(test::one_triangle().model, "many-nodes.gltf", GltfForm::embedded));
    doc = nlohmann::json::parse(in);
  }
  doc["nodes"] = nlohmann::json::array();
  doc["scenes"][0]["nodes"] = nlohmann::json::array();
  for (int n = 0; n < 20000; ++n) {
    doc["nodes"].push_back({{"mesh", 0}, {"translation", {n % 1000, n / 1000, 0}}});
    doc["scenes"][0]["nodes"].push_back(n);
  }
  const Scene s = load_scene(test::write_file("many-nodes.gltf", doc.dump()));
  ASSERT_EQ(s.meshes().size(), 1u);
  ASSERT_EQ(s.instances().size(), 20000u);
  EXPECT_EQ(Affine3d(s.instances().back().object_to_world).point({0, 0, 0}), Vec3d(999, 19, 0));
}

TEST(GltfLoader, ASparseAccessorNoPrimitiveReadsIsLeftAlone) {
  // A morph target's or an animation's sparse accessor is valid glTF the reader never reads;
  // only a sparse accessor a primitive reads is refused (bad-sparse.gltf).
  nlohmann::json doc;
  {
    std::ifstream in(written(test::one_triangle().model, "sparse-unused.gltf", GltfForm::embedded));
    doc = nlohmann::json::parse(in);
  }
  nlohmann::json extra = doc["accessors"][0];
  extra["sparse"] = {{"count", 1},
                     {"indices", {{"bufferView", 0}, {"componentType", 5123}}},
                     {"values", {{"bufferView", 0}}}};
  doc["accessors"].push_back(extra);
  const Scene s = load_scene(test::write_file("sparse-unused.gltf", doc.dump()));
  EXPECT_EQ(s.meshes().size(), 1u);
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
      {"bad-index.gltf",
       "$.meshes[0].primitives[0].indices: element 1: 3 is not a vertex index (the primitive has 3 vertices)"},
      {"bad-cycle.gltf", "$.nodes[1].children[0]: node 0 is its own ancestor (a cycle)"},
      {"bad-two-parents.gltf", "$.nodes[2].children[0]: node 0 is reached twice (a node may have one parent only)"},
      {"bad-missing-buffer.gltf",
       "$.buffers[0].uri: \"missing.bin\": hostile/missing.bin: cannot open: No such file or directory"},
      {"bad-device-uri.gltf", "$.buffers[0].uri: \"" + up.substr(0, 32) + "...\" lies outside the glTF's folder"},
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
      {"bad-uri-outside.gltf", "$.buffers[0].uri: \"../outside.bin\" lies outside the glTF's folder"},
      {"bad-uri-encoded.gltf",
       "$.buffers[0].uri: \"..%2Foutside.bin\" (\"../outside.bin\" decoded) lies outside the glTF's folder"},
      {"bad-translation-type.gltf", "$.nodes[0].translation[0]: \"a\" is not a number"},
      {"bad-scene-index.gltf", "$.scene: -2 names no scene (1 scenes)"},
      {"bad-negative-offset.gltf", "$.bufferViews[1].byteOffset: -4 is not an integer >= 0"},
      {"bad-emissive-strength.gltf",
       "$.materials[0].extensions.KHR_materials_emissive_strength.emissiveStrength: \"x\" is not a number >= 0"},
      {"bad-rotation-overflow.gltf",
       "$.nodes[0].rotation: its length 1.41421e+300 is not 1 (a rotation is a unit quaternion, within 0.00769)"},
      {"bad-index-max.gltf",
       "$.meshes[0].primitives[0].indices: element 1: 4294967295 is not a vertex index (the primitive has 3 "
       "vertices)"},
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

/// A buffer is read only from the glTF's folder and below: its URI, %-decoded as tinygltf
/// decodes it, may not climb out ("../", encoded slashes and dots, deep "../../"), be absolute,
/// or lead out through a symbolic link (to a file or a folder); a URI that goes out of a
/// subfolder and back in, and a link to a file inside the folder, are read.
TEST(GltfErrors, BufferUrisStayInTheFilesFolder) {
  const fs::path root = scratch() / "uris", folder = root / "scene";
  const std::string triangle = written(test::one_triangle().model, "uris/scene/triangle.gltf", GltfForm::external);
  fs::create_directories(root / "secret");
  fs::create_directories(folder / "sub");
  fs::copy_file(folder / "triangle.bin", root / "secret" / "private.bin", fs::copy_options::overwrite_existing);
  fs::copy_file(folder / "triangle.bin", folder / "x.bin", fs::copy_options::overwrite_existing);
  fs::create_symlink(root / "secret" / "private.bin", folder / "link.bin");
  fs::create_symlink(root / "secret", folder / "secret-folder");
  fs::create_symlink(folder / "x.bin", folder / "inside-link.bin");
  ASSERT_EQ(error_loading(triangle), "no error");
  const auto error_with = [&](const std::string& uri) {
    return error_loading(written(test::one_triangle().model, "uris/scene/case.gltf", GltfForm::embedded,
                                 [&](nlohmann::json& doc) { doc["buffers"][0]["uri"] = uri; }));
  };
  const std::string outside = " lies outside the glTF's folder";
  const std::string at = "uris/scene/case.gltf: $.buffers[0].uri: ";
  EXPECT_EQ(error_with("../secret/private.bin"), at + "\"../secret/private.bin\"" + outside);
  EXPECT_EQ(error_with("..%2Fsecret%2Fprivate.bin"),
            at + "\"..%2Fsecret%2Fprivate.bin\" (\"../secret/private.bin\" decoded)" + outside);
  EXPECT_EQ(error_with("%2e%2e/secret/private.bin"),
            at + "\"%2e%2e/secret/private.bin\" (\"../secret/private.bin\" decoded)" + outside);
  EXPECT_EQ(error_with("sub/../../secret/private.bin"), at + "\"sub/../../secret/private.bin\"" + outside);
  const std::string deep = "../../../../../../../../../../../../etc/passwd";
  EXPECT_EQ(error_with(deep), at + "\"" + deep.substr(0, 32) + "...\"" + outside);  // quoted URIs are cut at 32
  EXPECT_EQ(error_with("/etc/passwd"), at + "\"/etc/passwd\"" + outside);
  EXPECT_EQ(error_with("%2Fetc%2Fpasswd"), at + "\"%2Fetc%2Fpasswd\" (\"/etc/passwd\" decoded)" + outside);
  EXPECT_EQ(error_with("link.bin"), at + "\"link.bin\"" + outside + " once symbolic links are followed");
  EXPECT_EQ(error_with("secret-folder/private.bin"),
            at + "\"secret-folder/private.bin\"" + outside + " once symbolic links are followed");
  EXPECT_EQ(error_with("x.bin%00.png"), at + "\"x.bin%00.png\" (\"x.bin?.png\" decoded) holds a NUL byte");
  // Out of a subfolder and back in, existing or not, and a link that stays inside: read.
  for (const std::string uri :
       {"x.bin", "sub/../x.bin", "no-such-folder/../x.bin", "sub%2F..%2Fx.bin", "./x.bin", "inside-link.bin"})
    EXPECT_EQ(error_with(uri), "no error") << uri;
}

/// tinygltf 2.7 turns a value of the wrong type or range into a default without a word; each
/// is refused with the value's JSON path instead: offsets, strides, counts and lengths,
/// non-numbers in a node's transform, indices naming nothing, material and light values.
TEST(GltfErrors, ValuesOfTheWrongTypeOrRangeAreRefusedWithTheirPath) {
  using nlohmann::json;
  const std::vector<std::pair<std::function<void(json&)>, std::string>> cases = {
      {[](json& d) { d["bufferViews"][1]["byteOffset"] = -4; },
       "$.bufferViews[1].byteOffset: -4 is not an integer >= 0"},
      {[](json& d) { d["bufferViews"][0]["byteStride"] = -12; },
       "$.bufferViews[0].byteStride: -12 is not a byteStride (a multiple of 4 in [4, 252])"},
      {[](json& d) { d["bufferViews"][0]["byteStride"] = 14; },
       "$.bufferViews[0].byteStride: 14 is not a byteStride (a multiple of 4 in [4, 252])"},
      {[](json& d) { d["bufferViews"][0]["byteLength"] = "36"; },
       "$.bufferViews[0].byteLength: \"36\" is not an integer >= 1"},
      {[](json& d) { d["accessors"][0]["byteOffset"] = -12; }, "$.accessors[0].byteOffset: -12 is not an integer >= 0"},
      {[](json& d) { d["accessors"][0]["byteOffset"] = 1.5; }, "$.accessors[0].byteOffset: 1.5 is not an integer >= 0"},
      {[](json& d) { d["accessors"][0]["count"] = 0; }, "$.accessors[0].count: 0 is not an integer >= 1"},
      {[](json& d) { d["accessors"][1]["componentType"] = 5124; },
       "$.accessors[1].componentType: 5124 is not a componentType (5120, 5121, 5122, 5123, 5125, 5126)"},
      {[](json& d) { d["accessors"][0]["type"] = "VEC5"; },
       "$.accessors[0].type: \"VEC5\" is not an accessor type (SCALAR, VEC2, VEC3, VEC4, MAT2, MAT3, MAT4)"},
      {[](json& d) { d["accessors"][0]["bufferView"] = -1; },
       "$.accessors[0].bufferView: -1 names no bufferView (2 bufferViews)"},
      {[](json& d) { d["buffers"][0]["byteLength"] = 0; }, "$.buffers[0].byteLength: 0 is not an integer >= 1"},
      {[](json& d) {
         d["nodes"][0]["translation"] = {"a", 0, 0};
       },
       "$.nodes[0].translation[0]: \"a\" is not a number"},
      {[](json& d) {
         d["nodes"][0]["scale"] = {1, nullptr, 1};
       },
       "$.nodes[0].scale[1]: null is not a number"},
      {[](json& d) {
         d["nodes"][0]["rotation"] = {0, 0, true, 1};
       },
       "$.nodes[0].rotation[2]: true is not a number"},
      {[](json& d) {
         d["nodes"][0]["rotation"] = {0, 0, 1};
       },
       "$.nodes[0].rotation: 3 numbers, not 4"},
      {[](json& d) { d["nodes"][0]["matrix"] = "identity"; },
       "$.nodes[0].matrix: \"identity\" is not an array of 16 numbers"},
      {[](json& d) { d["nodes"][0]["mesh"] = 4294967296; }, "$.nodes[0].mesh: 4294967296 names no mesh (1 meshes)"},
      {[](json& d) { d["nodes"][0]["children"] = {-1}; }, "$.nodes[0].children[0]: -1 names no node (1 nodes)"},
      {[](json& d) { d["scene"] = -2; }, "$.scene: -2 names no scene (1 scenes)"},
      {[](json& d) { d["scene"] = 1; }, "$.scene: 1 names no scene (1 scenes)"},
      {[](json& d) { d["scene"] = "0"; }, "$.scene: \"0\" is not an index (an integer >= 0)"},
      {[](json& d) { d["scene"] = 0.0; }, "$.scene: 0.0 is not an index (an integer >= 0)"},
      {[](json& d) { d["scenes"][0]["nodes"] = {3}; }, "$.scenes[0].nodes[0]: 3 names no node (1 nodes)"},
      {[](json& d) { d["meshes"][0]["primitives"][0]["indices"] = 7; },
       "$.meshes[0].primitives[0].indices: 7 names no accessor (2 accessors)"},
      {[](json& d) { d["meshes"][0]["primitives"][0]["attributes"]["NORMAL"] = 2; },
       "$.meshes[0].primitives[0].attributes.NORMAL: 2 names no accessor (2 accessors)"},
      {[](json& d) { d["meshes"][0]["primitives"][0]["mode"] = 9; },
       "$.meshes[0].primitives[0].mode: 9 is not an integer in [0, 6]"},
      {[](json& d) { d["meshes"][0]["primitives"][0]["material"] = 0; },
       "$.meshes[0].primitives[0].material: 0 names no material (0 materials)"},
      {[](json& d) {
         d["materials"] = {{{"emissiveFactor", {1, 1, 1}},
                            {"extensions", {{"KHR_materials_emissive_strength", {{"emissiveStrength", "x"}}}}}}};
       },
       "$.materials[0].extensions.KHR_materials_emissive_strength.emissiveStrength: \"x\" is not a number >= 0"},
      {[](json& d) {
         d["materials"] = {{{"extensions", {{"KHR_materials_emissive_strength", {{"emissiveStrength", -1}}}}}}};
       },
       "$.materials[0].extensions.KHR_materials_emissive_strength.emissiveStrength: -1 is not a number >= 0"},
      {[](json& d) {
         d["materials"] = {{{"emissiveFactor", {2, 0, 0}}}};
       },
       "$.materials[0].emissiveFactor[0]: 2 is not a number in [0, 1]"},
      {[](json& d) {
         d["materials"] = {{{"pbrMetallicRoughness", {{"baseColorFactor", {1, 1, 1}}}}}};
       },
       "$.materials[0].pbrMetallicRoughness.baseColorFactor: 3 numbers, not 4"},
      {[](json& d) {
         d["materials"] = {{{"alphaMode", "blend"}}};
       },
       "$.materials[0].alphaMode: \"blend\" is not an alphaMode (OPAQUE, MASK, BLEND)"},
      {[](json& d) {
         d["cameras"] = {{{"type", "perspective"}, {"perspective", {{"yfov", "wide"}, {"znear", 0.1}}}}};
       },
       "$.cameras[0].perspective.yfov: \"wide\" is not a number > 0"},
      {[](json& d) {
         d["cameras"] = {{{"type", "perspective"}, {"perspective", {{"yfov", 0.5}}}}};
       },
       "$.cameras[0].perspective: has no \"znear\""},
      {[](json& d) {
         d["extensions"]["KHR_lights_punctual"]["lights"] = {{{"type", "point"}, {"intensity", -1}}};
       },
       "$.extensions.KHR_lights_punctual.lights[0].intensity: -1 is not a number >= 0"},
      {[](json& d) { d["nodes"][0]["extensions"]["KHR_lights_punctual"]["light"] = 0; },
       "$.nodes[0].extensions.KHR_lights_punctual.light: 0 names no light (0 lights)"},
      {[](json& d) { d["nodes"] = 5; }, "$.nodes: 5 is not an array"},
      {[](json& d) { d["nodes"][0] = "node"; }, "$.nodes[0]: \"node\" is not an object"},
      {[](json& d) { d.erase("asset"); }, "$: has no \"asset\""},
  };
  for (size_t i = 0; i < cases.size(); ++i) {
    SCOPED_TRACE(cases[i].second);
    const std::string name = "values/" + std::to_string(i) + ".gltf";
    EXPECT_EQ(error_loading(written(test::one_triangle().model, name, GltfForm::embedded, cases[i].first)),
              name + ": " + cases[i].second);
  }
}

/// A node's rotation must be a unit quaternion within glTF-Validator's 0.00769: one whose
/// length overflows a double when squared is refused, not normalised to the identity; one
/// within the tolerance is read as the rotation it nearly is.
TEST(GltfErrors, ARotationMustBeAUnitQuaternion) {
  const auto error_with = [](std::vector<double> q) {
    GltfBuilder b = test::one_triangle();
    b.model.nodes[0].rotation = std::move(q);
    return error_loading(written(b.model, "rotation.gltf", GltfForm::embedded));
  };
  const std::string at = "rotation.gltf: $.nodes[0].rotation: ";
  EXPECT_EQ(error_with({1e300, 0, 0, 1e300}),
            at + "its length 1.41421e+300 is not 1 (a rotation is a unit quaternion, within 0.00769)");
  EXPECT_EQ(error_with({-1.7e308, 1.7e308, 0, 0}),
            at + "its length inf is not 1 (a rotation is a unit quaternion, within 0.00769)");
  EXPECT_EQ(error_with({0, 0, 0, 2}), at + "its length 2 is not 1 (a rotation is a unit quaternion, within 0.00769)");
  EXPECT_EQ(error_with({1e-200, 0, 0, 0}),
            at + "its length 1e-200 is not 1 (a rotation is a unit quaternion, within 0.00769)");
  EXPECT_EQ(error_with({0, 0, 0, 0}), at + "a zero quaternion is no rotation");
  EXPECT_EQ(error_with({0.7071, 0, 0, 0.7071}), "no error");
  GltfBuilder b = test::one_triangle();
  b.model.nodes[0].rotation = {0, 0, 0, 1.005};
  const Scene s = load_scene(written(b.model, "rotation.gltf", GltfForm::embedded));
  expect_near(Vec3d(s.meshes()[0].positions[1]), {1, 0, 0}, 1e-7, "a near-unit quaternion normalised");
}

/// What tinygltf refused without a JSON path, or with an exception, is refused with one: a
/// GLB buffer of byteLength 0 (tinygltf's vector::at threw), a buffer longer than the GLB's
/// BIN chunk, an external file or data URI of another size than its byteLength, an index
/// accessor that does not exist; an empty file, a .glb too short for its headers or not a GLB.
TEST(GltfErrors, WhatTinygltfRefusesIsNamedWithItsPath) {
  using nlohmann::json;
  const std::string path = written(test::one_triangle().model, "faults/one.gltf", GltfForm::embedded);
  std::ifstream in(path);
  const json doc = json::parse(in);
  const std::string bin(42, '\0');
  const auto glb = [&](const std::string& name, const std::function<void(json&)>& change, const std::string& bytes) {
    json d = doc;
    d["buffers"][0].erase("uri");
    change(d);
    return error_loading(test::write_file("faults/" + name, test::glb_bytes(d, bytes)));
  };
  EXPECT_EQ(glb(
                "ok.glb", [](json&) {}, bin),
            "no error");
  EXPECT_EQ(glb(
                "zero.glb", [](json& d) { d["buffers"][0]["byteLength"] = 0; }, bin),
            "faults/zero.glb: $.buffers[0].byteLength: 0 is not an integer >= 1");
  EXPECT_EQ(glb(
                "long.glb", [](json& d) { d["buffers"][0]["byteLength"] = 100; }, bin),
            "faults/long.glb: $.buffers[0].byteLength: 100 bytes, more than the GLB's BIN chunk holds (44)");
  EXPECT_EQ(glb(
                "no-bin.glb", [](json&) {}, ""),
            "faults/no-bin.glb: $.buffers[0]: has no \"uri\", and the GLB has no BIN chunk");
  EXPECT_EQ(glb(
                "indices.glb", [](json& d) { d["meshes"][0]["primitives"][0]["indices"] = 2; }, bin),
            "faults/indices.glb: $.meshes[0].primitives[0].indices: 2 names no accessor (2 accessors)");
  const auto gltf = [&](const std::string& name, const std::function<void(json&)>& change) {
    return error_loading(written(test::one_triangle().model, "faults/" + name, GltfForm::embedded, change));
  };
  EXPECT_EQ(gltf("data.gltf", [](json& d) { d["buffers"][0]["byteLength"] = 50; }),
            "faults/data.gltf: $.buffers[0].uri: its data holds 42 bytes, not the 50 of its byteLength");
  written(test::one_triangle().model, "faults/external.gltf", GltfForm::external);
  EXPECT_EQ(gltf("size.gltf",
                 [](json& d) {
                   d["buffers"][0]["uri"] = "external.bin";
                   d["buffers"][0]["byteLength"] = 50;
                 }),
            "faults/size.gltf: $.buffers[0].uri: \"external.bin\": faults/external.bin: 42 bytes, not the 50 its "
            "byteLength says");
  EXPECT_EQ(gltf("no-uri.gltf", [](json& d) { d["buffers"][0].erase("uri"); }),
            "faults/no-uri.gltf: $.buffers[0]: has no \"uri\" (a .gltf's buffer names its data)");
  EXPECT_EQ(error_loading(test::write_file("faults/empty.glb", "")), "faults/empty.glb: empty file");
  EXPECT_EQ(error_loading(test::write_file("faults/empty.gltf", "")), "faults/empty.gltf: empty file");
  EXPECT_EQ(error_loading(test::write_file("faults/short.glb", "glT")),
            "faults/short.glb: truncated GLB: 3 bytes, its headers need 20");
  EXPECT_EQ(error_loading(test::write_file("faults/text.glb", "{\"asset\": {\"version\": \"2.0\"}}")),
            "faults/text.glb: not a GLB: its first 4 bytes are not \"glTF\"");
  EXPECT_EQ(error_loading(test::write_file("faults/tiny.gltf", "{}")), "faults/tiny.gltf: $: has no \"asset\"");
  EXPECT_EQ(error_loading(test::write_file("faults/broken.gltf", "{\"asset\": ")),
            "faults/broken.gltf: line 1, column 11: syntax error while parsing value - unexpected end of input; "
            "expected '[', '{', or a literal");
}

/// tinygltf builds every object the JSON lists, each far larger than its text: an empty
/// material "{}," is 3 bytes, a tinygltf::Material 2,144 (tinygltf 2.7, x86-64), so 130,000 of
/// them in a 0.4 MB file would take about 270 MiB, more than the budget of 32 bytes per byte
/// of input, at least 256 MiB. Refused before tinygltf reads anything: before it would find
/// that the buffer it reads first is missing. The bytes of an external buffer count as input:
/// with a 16 MiB one the same materials are allowed, and only the missing buffer is refused.
TEST(GltfErrors, ObjectsThatWouldTakeFarMoreMemoryThanTheFileAreRefusedUpFront) {
  nlohmann::json doc;
  {
    std::ifstream in(written(test::one_triangle().model, "memory/one.gltf", GltfForm::embedded));
    doc = nlohmann::json::parse(in);
  }
  doc["materials"] = nlohmann::json::array();
  for (int m = 0; m < 130000; ++m) doc["materials"].push_back(nlohmann::json::object());
  const auto message = [](const std::string& name, uint64_t input) {
    return "memory/" + name + ": $.materials: 130000 materials would make tinygltf take about 270 MiB, more than " +
           "the 256 MiB allowed for " + std::to_string(input) +
           " bytes of input (32 bytes per byte of input, at least 256 MiB)";
  };
  const std::string data = test::write_file("memory/data.gltf", doc.dump());
  EXPECT_EQ(error_loading(data), message("data.gltf", fs::file_size(data)));
  doc["buffers"][0]["uri"] = "missing.bin";
  const std::string missing = test::write_file("memory/missing.gltf", doc.dump());
  EXPECT_EQ(error_loading(missing), message("missing.gltf", fs::file_size(missing) + 42));
  doc["buffers"][0]["byteLength"] = 16 << 20;
  EXPECT_EQ(error_loading(test::write_file("memory/large.gltf", doc.dump())),
            "memory/large.gltf: $.buffers[0].uri: \"missing.bin\": memory/missing.bin: cannot open: No such file or "
            "directory");
}

/// Indices come from an accessor of unsigned integers (componentType 5121, 5123, 5125): float
/// and signed indices are refused, not truncated; a uint32 index naming no vertex, 0xFFFFFFFF
/// included, is refused with its value as stored.
TEST(GltfErrors, IndicesAreUnsignedIntegersNamingAVertex) {
  for (const int type : {TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_COMPONENT_TYPE_BYTE, TINYGLTF_COMPONENT_TYPE_SHORT}) {
    GltfBuilder b = test::one_triangle();
    const std::vector<float> idx{0.0f, 1.0f, 2.9f};
    const int view = b.view(idx.data(), 12);
    b.model.meshes[0].primitives[0].indices =
        b.accessor(view, type, TINYGLTF_TYPE_SCALAR, type == TINYGLTF_COMPONENT_TYPE_FLOAT ? 3 : 2);
    EXPECT_EQ(error_loading(written(b.model, "float-indices.gltf", GltfForm::embedded)),
              "float-indices.gltf: $.accessors[2].componentType: " + std::to_string(type) +
                  " is not a component type $.meshes[0].primitives[0].indices can have (5121, 5123, 5125)");
  }
  for (const uint32_t bad : {0xFFFFFFFFu, 0x80000000u, 3u}) {
    GltfBuilder b = test::one_triangle();
    b.model.meshes[0].primitives[0].indices = b.indices({0, 1, 2, 2, bad, 0}, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT);
    EXPECT_EQ(error_loading(written(b.model, "big-index.gltf", GltfForm::embedded)),
              "big-index.gltf: $.meshes[0].primitives[0].indices: element 4: " + std::to_string(bad) +
                  " is not a vertex index (the primitive has 3 vertices)");
  }
}

/// Warnings of one kind (the same words at paths differing only in their indices) are one
/// line with a count: 2,000 chained nodes scaling by 2 each, whose transforms stop being
/// invertible from node 341 on (the determinant 8^342 overflows), give one warning, not 1,659.
TEST(GltfWarnings, RepeatedWarningsAreOneLineWithACount) {
  GltfBuilder b;
  const int mesh = b.mesh({GltfBuilder::primitive(b.vectors({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}))});
  b.scene({b.node(mesh, {}, {}, {2, 2, 2})});
  for (int n = 1; n < 2000; ++n) {
    b.model.nodes.back().children = {n};
    b.node(n < 341 ? -1 : mesh, {}, {}, {2, 2, 2});
  }
  b.model.meshes.push_back(b.model.meshes[0]);  // a second mesh, placed once, keeps the file loading
  b.model.nodes[0].mesh = 1;
  testing::internal::CaptureStderr();
  const std::string error = error_loading(written(b.model, "chain.gltf", GltfForm::embedded));
  const std::string printed = testing::internal::GetCapturedStderr();
  EXPECT_EQ(error, "no error");
  EXPECT_EQ(printed, "raypack: warning: " + (scratch() / "chain.gltf").string() +
                         ": $.nodes[341]: its transform is singular (a zero scale) or too large to invert; its mesh "
                         "is not placed (and 1,658 more nodes like it)\n");
}

}  // namespace
}  // namespace rp
