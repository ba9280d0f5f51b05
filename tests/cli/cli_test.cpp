// The raypack command as a user runs it: exit statuses, one-line errors, real images.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "engine/image_io.h"

namespace {

namespace fs = std::filesystem;

struct Result {
  int status;
  std::string output;  // stdout and stderr
};

Result run(const std::string& args) {
  const std::string cmd = std::string(RAYPACK_EXE) + " " + args + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return {-1, "popen failed"};
  std::string out;
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
  const int st = pclose(p);
  return {WIFEXITED(st) ? WEXITSTATUS(st) : -1, out};
}

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("raypack-cli-" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(Cli, RenderWritesAnImageOfTheRequestedSizeThatIsNotBlank) {
  const fs::path out = dir_ / "small.png";
  const Result r = run("render --resolution 96x64 --spp 1 -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  ASSERT_TRUE(fs::exists(out));
  const rp::Image img = rp::read_image(out.string());
  EXPECT_EQ(img.width, 96);
  EXPECT_EQ(img.height, 64);
  float lo = 1e9f, hi = -1e9f;
  for (float c : img.rgb) lo = std::min(lo, c), hi = std::max(hi, c);
  EXPECT_GT(hi - lo, 0.3f) << "the image is blank or nearly so";
  // Nothing but the image is left behind (no temporary files).
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);
}

std::string file_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST_F(Cli, RenderWritesTheSameExrBytesForOneAndTwoThreads) {
  const fs::path one = dir_ / "one.exr", two = dir_ / "two.exr";
  Result r = run("render --resolution 40x24 --spp 4 --seed 3 -q -t 1 -o " + one.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(r.output.empty()) << r.output;
  r = run("render --resolution 40x24 --spp 4 --seed 3 -q -t 2 -o " + two.string());
  ASSERT_EQ(r.status, 0) << r.output;
  const rp::Image img = rp::read_image(one.string());
  EXPECT_EQ(img.width, 40);
  EXPECT_EQ(img.height, 24);
  const std::string a = file_bytes(one), b = file_bytes(two);
  EXPECT_GT(a.size(), 1000u);
  EXPECT_TRUE(a == b) << "EXR files differ between 1 and 2 threads";
}

TEST_F(Cli, UnknownBackendIsAOneLineErrorWithStatusTwo) {
  const Result r = run("render --backend nope -o " + (dir_ / "x.png").string());
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.output, "raypack: --backend: unknown backend 'nope' (available: embree, simd)\n");
  EXPECT_FALSE(fs::exists(dir_ / "x.png"));
}

TEST_F(Cli, BadFlagValuesAreOneLineErrorsWithStatusTwo) {
  for (const std::string args : {"render --resolution 10by10", "render --variant fastest", "render --backend simd --variant robust", "render --resolution 0x10",
                                 "render --resolution 100000x100000", "render --spp 0", "render --spp abc",
                                 "render --threads -1", "render --no-such-flag", "frobnicate"}) {
    const Result r = run(args + " -o " + (dir_ / "x.png").string());
    EXPECT_EQ(r.status, 2) << args << ": " << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << args << ": " << r.output;
    EXPECT_EQ(r.output.rfind("raypack: ", 0), 0u) << args << ": " << r.output;
  }
  EXPECT_FALSE(fs::exists(dir_ / "x.png"));
}

TEST_F(Cli, MissingSceneFileIsAnErrorWithStatusOne) {
  const fs::path scene = dir_ / "nope.obj";
  const Result r = run("render --scene " + scene.string() + " -o " + (dir_ / "x.png").string());
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_EQ(r.output, "raypack: " + scene.string() + ": cannot open: No such file or directory\n");
  EXPECT_FALSE(fs::exists(dir_ / "x.png"));
}

TEST_F(Cli, RendersAnObjFileWithTheSimdBackend) {
  const fs::path scene = dir_ / "quad.obj", out = dir_ / "quad.png";
  std::ofstream(scene) << "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3 4\n";
  const Result r = run("render --backend simd --scene " + scene.string() + " --resolution 32x32 -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("with simd/default"), std::string::npos) << r.output;
  const rp::Image img = rp::read_image(out.string());
  EXPECT_EQ(img.width, 32);
  EXPECT_EQ(img.height, 32);
}

TEST_F(Cli, UnwritableOutputIsAnErrorWithStatusOneAndNoFile) {
  const fs::path out = dir_ / "missing-dir" / "x.png";
  const Result r = run("render --resolution 16x16 -o " + out.string());
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find(out.string()), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(Cli, TraceWritesOneHitPerRayAsTheBackendFindsThem) {
  const fs::path rays = dir_ / "rays.csv", hits = dir_ / "hits.csv", bin = dir_ / "hits.bin";
  // Down the y axis onto the default scene's ground plane (y = 0) from above, and one miss.
  std::ofstream(rays) << "ox,oy,oz,dx,dy,dz,tnear,tfar\n"
                      << "5,10,5,0,-1,0,0,inf\n"
                      << "5,10,5,0,1,0,0,inf\n";
  Result r = run("trace --rays " + rays.string() + " -o " + hits.string() + " --backend simd");
  ASSERT_EQ(r.status, 0) << r.output;
  std::ifstream in(hits);
  std::string header, first, second;
  std::getline(in, header);
  std::getline(in, first);
  std::getline(in, second);
  EXPECT_EQ(header, "t,prim_id,u,v,ng_x,ng_y,ng_z");
  EXPECT_EQ(first.rfind("10,", 0), 0u) << first;  // t = 10 on the plane
  EXPECT_EQ(first.substr(first.size() - 6), ",0,1,0") << first;  // normal +y
  EXPECT_EQ(second, "inf,-1,0,0,0,0,0");
  r = run("trace --rays " + rays.string() + " -o " + bin.string() + " -q");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(fs::file_size(bin), 16u + 2u * 28u);
}

TEST_F(Cli, TraceRejectsAMalformedRayFileWithStatusOne) {
  const fs::path rays = dir_ / "bad.csv";
  std::ofstream(rays) << "ox,oy,oz,dx,dy,dz,tnear,tfar\n1,2,3\n";
  const Result r = run("trace --rays " + rays.string() + " -o " + (dir_ / "h.csv").string());
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(r.output, "raypack: " + rays.string() + ": line 2: 3 values, expected 8\n");
  EXPECT_FALSE(fs::exists(dir_ / "h.csv"));
}

TEST_F(Cli, DiffPrintsTheTableWritesJsonAndAnImageAndHonoursMinAgreement) {
  const fs::path json = dir_ / "d.json", image = dir_ / "d.png";
  Result r = run("diff --rays primary --count 4096 -a embree -b simd --json " + json.string() + " --image " +
                 image.string() + " --min-agreement 99");
  ASSERT_EQ(r.status, 0) << r.output;
  for (const char* word : {"agree", "tie", "hit/miss", "wrong primitive", "t error", "reference supports"})
    EXPECT_NE(r.output.find(word), std::string::npos) << word << "\n" << r.output;
  EXPECT_NE(file_bytes(json).find("\"agreement\""), std::string::npos);
  EXPECT_EQ(rp::read_image(image.string()).width, 64);
  // A backend against the reference itself, demanding more agreement than float can give on
  // a scene with shared edges, must fail with status 3 when it falls short; 0 disagreements
  // would pass, so check the status matches the printed agreement.
  r = run("diff --rays random --count 20000 -a simd -b reference --min-agreement 100");
  const bool perfect = r.output.find("agreement 100.00000%") != std::string::npos;
  EXPECT_EQ(r.status, perfect ? 0 : 3) << r.output;
  r = run("diff --rays nowhere.rays");
  EXPECT_EQ(r.status, 1) << r.output;
}

TEST_F(Cli, InfoCountsTheScene) {
  const fs::path scene = dir_ / "two.obj";
  // A quad (2 triangles), a degenerate triangle, and an unreferenced vertex.
  std::ofstream(scene) << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 5 5 5\nf 1 2 3 4\nf 1 2 2\n";
  const Result r = run("info " + scene.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("triangles    3 in 1 mesh(es), 4 vertices"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("degenerate   1 zero-area triangles"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("raypack: warning: " + scene.string() + ": 1 zero-area triangle kept; no ray can hit it\n"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("bounds       (0, 0, 0) - (1, 1, 0)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("\nembree "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("\nsimd "), std::string::npos) << r.output;
}

TEST_F(Cli, RenderWritesAovsAsOneExr) {
  const fs::path out = dir_ / "b.png", aov = dir_ / "aov.exr";
  Result r = run("render --resolution 24x16 -q -o " + out.string() + " --aov " + aov.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_GT(fs::file_size(aov), 100u);
  r = run("render --resolution 24x16 -q -o " + out.string() + " --aov " + (dir_ / "aov.png").string());
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("AOVs are written as OpenEXR"), std::string::npos) << r.output;
}

TEST_F(Cli, EveryCameraAndSamplerRenders) {
  for (const std::string args : {"--camera panoramic", "--camera fisheye --fisheye-fov 200",
                                 "--camera thin-lens --aperture 0.2 --focus-distance 8 --spp 4",
                                 "--sampler uniform --spp 4", "--sampler random --spp 2", "--sampler adaptive",
                                 "--eye 0,2,9 --look-at 0,1,0 --up 0,1,0 --fov 50"}) {
    const fs::path out = dir_ / "c.png";
    const Result r = run("render --resolution 32x24 -o " + out.string() + " " + args);
    EXPECT_EQ(r.status, 0) << args << ": " << r.output;
    EXPECT_EQ(rp::read_image(out.string()).width, 32) << args;
  }
  for (const std::string args : {"--camera orthographic", "--sampler uniform --spp 3", "--eye 1,2", "--fov 200",
                                 "--eye 0,1,0 --look-at 0,1,0"}) {
    const Result r = run("render --resolution 32x24 -o " + (dir_ / "d.png").string() + " " + args);
    EXPECT_EQ(r.status, 2) << args << ": " << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << args << ": " << r.output;
  }
}

TEST_F(Cli, BenchWritesJsonAndChartsThatChartRedraws) {
  const fs::path json = dir_ / "b.json", chart = dir_ / "c.png", again = dir_ / "again.png";
  Result r = run("bench --size 16 --min-runs 1 --max-runs 2 --json " + json.string() + " --chart " + chart.string());
  ASSERT_EQ(r.status, 0) << r.output;
  for (const char* word : {"simd packet", "simd single", "embree rtcIntersect8", "embree rtcIntersect1", "embree robust 1",
                           "bytes/prim", "primary", "shadow", "diffuse"})
    EXPECT_NE(r.output.find(word), std::string::npos) << word << "\n" << r.output;
  const std::string text = file_bytes(json);
  for (const char* key : {"\"machine\"", "\"mrays_per_s\"", "\"mismatch_rate\"", "\"spread\"", "\"bytes_per_prim\"",
                          "\"build_seconds\""})
    EXPECT_NE(text.find(key), std::string::npos) << key;
  for (const fs::path& p : {chart, dir_ / "c-scaling.png"})
    EXPECT_GT(fs::exists(p) ? fs::file_size(p) : 0u, 1000u) << p;
  EXPECT_FALSE(fs::exists(dir_ / "c.svg")) << "a .png chart is drawn as PNG only";
  EXPECT_EQ(rp::read_image(chart.string()).width, 1500);
  r = run("chart " + json.string() + " -o " + again.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(fs::exists(again));
  // The format follows the extension: an SVG named .svg, the PNG beside it untouched.
  const std::string png_bytes = file_bytes(chart);
  r = run("chart " + json.string() + " -o " + (dir_ / "c.svg").string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(file_bytes(dir_ / "c.svg").rfind("<?xml", 0), 0u);
  EXPECT_EQ(file_bytes(dir_ / "c-scaling.svg").rfind("<?xml", 0), 0u);
  EXPECT_EQ(file_bytes(chart), png_bytes);
  r = run("chart " + json.string() + " -o " + (dir_ / "c.jpg").string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("unknown chart format '.jpg'"), std::string::npos) << r.output;
  std::ofstream(dir_ / "bad.json") << "{\"not\": 1}";
  r = run("chart " + (dir_ / "bad.json").string() + " -o " + again.string());
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("not a raypack bench file"), std::string::npos) << r.output;
}

TEST_F(Cli, HelpAndVersion) {
  Result r = run("--help");
  EXPECT_EQ(r.status, 0);
  EXPECT_NE(r.output.find("render"), std::string::npos);
  r = run("--version");
  EXPECT_EQ(r.status, 0);
  EXPECT_EQ(r.output.rfind("raypack ", 0), 0u) << r.output;
  r = run("backends");
  EXPECT_EQ(r.status, 0);
  EXPECT_NE(r.output.find("embree"), std::string::npos);
}

}  // namespace
