// load_scene: the embedded default, dispatch by extension, lights from the bounds; and the real
// models of RAYPACK_SHARED_SCENES (CMake; ../shared/scenes by default) against the triangle
// counts of its README, when present.

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

#include "base/error.h"
#include "io/loaders/load.h"
#include "ply_files.h"
#include "scratch.h"
#include "tests/support/build_paths.h"
#include "tests/support/error_of.h"

namespace rp {
namespace {

namespace fs = std::filesystem;
using namespace rp::test;

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
  EXPECT_EQ(error_of([] { load_scene("model.stl"); }), "model.stl: unknown scene format '.stl' (.obj, .ply, .json, .gltf, .glb)");
  EXPECT_EQ(error_of([] { load_scene("model"); }), "model: unknown scene format '' (.obj, .ply, .json, .gltf, .glb)");
  EXPECT_EQ(error_of([] { load_scene("scenes.d/model"); }),
            "scenes.d/model: unknown scene format '' (.obj, .ply, .json, .gltf, .glb)");
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

TEST(LoadScene, AZUpFileIsLitFromAboveItsFrontWhenTheUpAxisIsZ) {
  const std::string path = write_file("zup.ply", cube_ply(PlyFormat::little_endian, CubeLayout::plain));
  const Scene s = load_scene(path, 2);
  EXPECT_EQ(s.up_axis(), 2);
  const Box3f b = s.bounds();
  const PointLight& key = s.point_lights()[0];
  EXPECT_GT(key.position.z, b.hi.z);  // above: +Z
  EXPECT_LT(key.position.y, b.lo.y);  // in front: -Y
  EXPECT_GT(key.position.x, b.center().x);  // a little to the right: +X
  EXPECT_LT(s.directional_lights()[0].direction.z, 0.0f);  // the fill from above
  EXPECT_EQ(load_scene(path).up_axis(), 1);  // Y unless asked
}

TEST(LoadScene, GltfFilesAreReadByTheirExtension) {
  EXPECT_EQ(error_of([] { load_scene("model.stl"); }),
            "model.stl: unknown scene format '.stl' (.obj, .ply, .json, .gltf, .glb)");
}

// --- the real models ---------------------------------------------------------------------------

struct RealModel {
  const char* file;
  uint32_t triangles;  ///< from ../shared/scenes/README.md
};

class RealModels : public testing::TestWithParam<RealModel> {};

TEST_P(RealModels, TriangleCountMatchesTheReadme) {
  const fs::path dir = kSharedScenes;
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
  for (const MeshView& m : s.meshes()) vertices += m.positions.size();
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
    for (const MeshView& view : s.meshes()) {
      const TriangleMesh m = to_triangle_mesh(view);
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
