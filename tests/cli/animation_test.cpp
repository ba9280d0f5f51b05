// An animated glTF through the raypack command: `trace --time` against a trace of the file
// flattened by hand at that time (tests/support/animated_gltf.h: the tests' own sampling),
// byte for byte on both backends; `render --frames` against still renders at each frame's
// time; the frame names; `info` on an animated file; and the flags and files refused.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "render/image_io.h"
#include "tests/support/animated_gltf.h"
#include "tests/support/raypack_command.h"
#include "tests/support/temp_dir.h"

namespace {

namespace fs = std::filesystem;
using rp::test::file_bytes;
using rp::test::run_raypack;
using Result = rp::test::ShellResult;

/// Each test in a fresh folder of its own, holding the animated scene (animated.gltf).
class CliAnimation : public ::testing::Test {
 protected:
  void SetUp() override { rp::test::write_gltf(animation_.model, scene_.string(), rp::test::GltfForm::embedded); }

  /// The still copy of the scene at `seconds`, written as `name`; its path.
  std::string still(double seconds, const std::string& name) const {
    const std::string path = tmp_ / name;
    rp::test::write_gltf(animation_.still(seconds), path, rp::test::GltfForm::embedded);
    return path;
  }

  rp::test::TempDir tmp_;
  fs::path dir_ = tmp_.dir;
  rp::test::AnimatedGltf animation_ = rp::test::animated_scene();
  fs::path scene_ = dir_ / "animated.gltf";
};

/// Ends with one newline and holds no other.
bool one_line(const std::string& s) { return std::count(s.begin(), s.end(), '\n') == 1 && s.back() == '\n'; }

TEST_F(CliAnimation, TraceAtATimeIsTheTraceOfTheFileFlattenedByHandOnEveryBackend) {
  // A grid of rays down -z, a little slanted, over every place the meshes go.
  const fs::path rays = dir_ / "rays.csv";
  {
    std::ofstream out(rays);
    out << "ox,oy,oz,dx,dy,dz,tnear,tfar\n";
    for (int y = 0; y < 48; ++y)
      for (int x = 0; x < 48; ++x)
        out << -5 + x * 10.0 / 47 << "," << -5 + y * 10.0 / 47 << ",10,0.05,-0.03,-1,0,inf\n";
  }
  const std::string hits = (dir_ / "hits.bin").string(), want = (dir_ / "want.bin").string();
  for (const double t : {0.5, 0.3, 0.8}) {
    const std::string flat = still(t, "still.gltf");
    for (const std::string backend : {"simd", "embree"}) {
      SCOPED_TRACE(backend + " at " + std::to_string(t));
      const std::string common = " --backend " + backend + " --rays " + rays.string() + " -q -o ";
      Result r = run_raypack("trace --scene " + scene_.string() + " --time " + std::to_string(t) + common + hits);
      ASSERT_EQ(r.status, 0) << r.output;
      r = run_raypack("trace --scene " + flat + common + want);
      ASSERT_EQ(r.status, 0) << r.output;
      EXPECT_GT(file_bytes(hits).size(), 16u + 48u * 48u * 32u - 1u);
      EXPECT_TRUE(file_bytes(hits) == file_bytes(want)) << "the posed scene's hits are not its still copy's";
      // And the pose matters: the rest pose's hits differ.
      r = run_raypack("trace --scene " + scene_.string() + common + want);
      ASSERT_EQ(r.status, 0) << r.output;
      EXPECT_FALSE(file_bytes(hits) == file_bytes(want));
    }
  }
}

TEST_F(CliAnimation, EachFrameIsTheStillRenderAtItsTime) {
  const std::string common = " --resolution 40x32 --spp 2 -q --scene " + scene_.string();
  for (const std::string backend : {"simd", "embree"}) {
    SCOPED_TRACE(backend);
    const Result r = run_raypack("render --frames 0:3 --fps 4 --backend " + backend + common + " -o " +
                                 (dir_ / "frame-##.exr").string());
    ASSERT_EQ(r.status, 0) << r.output;
    std::vector<std::vector<float>> frames;
    for (int k = 0; k < 4; ++k) {
      const fs::path frame = dir_ / ("frame-0" + std::to_string(k) + ".exr"), want = dir_ / "still.exr";
      const Result s = run_raypack("render --time " + std::to_string(k / 4.0) + " --backend " + backend + common +
                                   " -o " + want.string());
      ASSERT_EQ(s.status, 0) << s.output;
      ASSERT_TRUE(fs::exists(frame)) << frame;
      frames.push_back(rp::read_image(frame.string()).rgb);
      EXPECT_TRUE(frames.back() == rp::read_image(want.string()).rgb) << "frame " << k;
    }
    EXPECT_FALSE(frames[0] == frames[1]) << "the scene does not move between frames";
  }
}

TEST_F(CliAnimation, TheRunOfHashesInTheOutputIsTheFrameNumber) {
  const std::string common = "render --resolution 8x8 -q --scene " + scene_.string();
  ASSERT_EQ(run_raypack(common + " --frames 9:10 -o " + (dir_ / "f-#.png").string()).status, 0);
  ASSERT_EQ(run_raypack(common + " --frames 3:3 -o " + (dir_ / "g-###.png").string()).status, 0);
  ASSERT_EQ(run_raypack(common + " --frames 2:2 -o " + (dir_ / "plain.png").string()).status, 0);
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir_)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"animated.gltf", "f-10.png", "f-9.png", "g-003.png", "plain.png"}));
}

TEST_F(CliAnimation, BadTimesFramesAndNamesAreOneLineErrorsBeforeAnyWork) {
  const std::string d = dir_.string() + "/", scene = " --scene " + scene_.string();
  const std::pair<std::string, std::string> cases[] = {
      {"render --time abc -o " + d + "x.png", "--time: 'abc' is not a number of seconds (a finite number)"},
      {"render --time inf -o " + d + "x.png", "--time: 'inf' is not a number of seconds (a finite number)"},
      {"trace --time nan --rays " + d + "r.csv -o " + d + "h.csv", "--time: 'nan' is not a number of seconds"},
      {"diff --time 1s", "--time: '1s' is not a number of seconds"},
      {"info --time x", "--time: 'x' is not a number of seconds"},
      {"render --frames 0:3 -o " + d + "x.png", "-o: '" + d + "x.png' has no run of '#' to number 4 frames by"},
      {"render --frames 0:1 -o " + d + "x-#.png --aov " + d + "a.exr",
       "--aov: '" + d + "a.exr' has no run of '#' to number 2 frames by"},
      {"render --frames 0:1 -o " + d + "x-#-#.png", "-o: '" + d + "x-#-#.png' has 2 runs of '#'"},
      {"render --frames 3:1 -o " + d + "x-#.png",
       "--frames: '3:1' is not FIRST:LAST (frame numbers, 0 <= FIRST <= LAST)"},
      {"render --frames 1 -o " + d + "x-#.png", "--frames: '1' is not FIRST:LAST"},
      {"render --frames a:b -o " + d + "x-#.png", "--frames: 'a:b' is not FIRST:LAST"},
      {"render --frames 0:1 --time 2 -o " + d + "x-#.png", "--time excludes --frames"},
      {"render --fps 30 -o " + d + "x.png", "--fps requires --frames"},
      {"render --frames 0:1 --fps 0 -o " + d + "x-#.png", "--fps: Value 0 not in range"},
      {"render --frames 0:1 --measure-traces -o " + d + "x-#.png",
       "--measure-traces: times the traces of one image; not with --frames"},
  };
  for (const auto& [args, message] : cases) {
    const Result r = run_raypack(args + scene);
    EXPECT_EQ(r.status, 2) << args << ": " << r.output;
    EXPECT_EQ(r.output.rfind("raypack: " + message, 0), 0u) << args << ": " << r.output;
    EXPECT_TRUE(one_line(r.output)) << args << ": " << r.output;
  }
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1) << "only the scene";
}

TEST_F(CliAnimation, InfoSaysHowTheSceneIsAnimatedAndPosesItAtATime) {
  Result r = run_raypack("info --no-backends " + scene_.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("\nanimation    1 animation(s), 5 channel(s) moving 3 node(s), 1 s long; shown at its "
                          "rest pose\n"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("instances    5 placing 2 instanced mesh(es)"), std::string::npos) << r.output;
  const std::string rest = r.output.substr(r.output.find("bounds"));
  r = run_raypack("info --no-backends --time 0.5 " + scene_.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("1 s long; shown at 0.5 s\n"), std::string::npos) << r.output;
  EXPECT_NE(r.output.substr(r.output.find("bounds")), rest) << "the pose moves the bounds";
  // A still file says nothing of animation.
  std::ofstream(dir_ / "still.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  r = run_raypack("info --no-backends --time 2 " + (dir_ / "still.obj").string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(r.output.find("animation"), std::string::npos) << r.output;
}

TEST_F(CliAnimation, DiffComparesTheBackendsOnThePosedScene) {
  const Result r = run_raypack("diff --count 512 -a embree -b simd --time 0.25 --scene " + scene_.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("\n512 rays, embree/default (A) vs simd/default (B)"), std::string::npos) << r.output;
}

TEST_F(CliAnimation, AFileThatCannotBeAnimatedFailsEveryCommandWithOneLine) {
  // A skinned node, and a sampler whose times go back.
  const fs::path skinned = dir_ / "skinned.gltf", backwards = dir_ / "backwards.gltf";
  rp::test::write_gltf(animation_.model, skinned.string(), rp::test::GltfForm::embedded, [](nlohmann::json& doc) {
    doc["skins"] = {{{"joints", {4}}}};
    doc["nodes"][4]["skin"] = 0;
  });
  tinygltf::Model bad = animation_.model;
  const tinygltf::Accessor& input = bad.accessors[size_t(bad.animations[0].samplers[3].input)];
  const float again = 0.5f;  // node 3's keyframe times 0, 0.5, 1 become 0, 0.5, 0.5
  std::memcpy(&bad.buffers[0].data[bad.bufferViews[size_t(input.bufferView)].byteOffset + 8], &again, 4);
  rp::test::write_gltf(bad, backwards.string(), rp::test::GltfForm::embedded);
  const std::pair<fs::path, std::string> files[] = {
      {skinned, "$.nodes[4].skin: skinned meshes are not supported"},
      {backwards,
       "$.animations[0].samplers[3].input: keyframe 2: its time 0.5 s is not after keyframe 1's (0.5 s); times must "
       "increase"}};
  std::ofstream(dir_ / "r.csv") << "ox,oy,oz,dx,dy,dz\n0,0,5,0,0,-1\n";
  for (const auto& [file, message] : files)
    for (const std::string& command : {"render -o " + (dir_ / "x.png").string(),
                                       "trace --rays " + (dir_ / "r.csv").string() + " -o " + (dir_ / "h.csv").string(),
                                       std::string("diff --count 64"), std::string("info")}) {
      const Result r = run_raypack(command + " --scene " + file.string());
      EXPECT_EQ(r.status, 1) << command << ": " << r.output;
      EXPECT_EQ(r.output, "raypack: " + file.string() + ": " + message + "\n") << command;
    }
  EXPECT_FALSE(fs::exists(dir_ / "x.png") || fs::exists(dir_ / "h.csv"));
}

}  // namespace
