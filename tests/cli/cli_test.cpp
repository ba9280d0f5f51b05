// The raypack command as a user runs it: exit statuses, one-line errors, real images.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <tuple>

#include "base/text.h"
#include "io/rayfile.h"
#include "render/image_io.h"
#include "tests/support/build_paths.h"
#include "tests/support/gltf_files.h"
#include "tests/support/raypack_command.h"
#include "tests/support/sanitized.h"
#include "tests/support/shell.h"
#include "tests/support/temp_dir.h"

namespace {

namespace fs = std::filesystem;

using Result = rp::test::ShellResult;

using rp::test::file_bytes;
using rp::test::run_raypack;

/// Each test in a fresh folder of its own (mkdtemp), so that two runs of the suite on one
/// machine (two clones, CI beside a developer) never share one.
class Cli : public ::testing::Test {
 protected:
  rp::test::TempDir tmp_;
  fs::path dir_ = tmp_.dir;
};

TEST_F(Cli, RenderWritesAnImageOfTheRequestedSizeThatIsNotBlank) {
  const fs::path out = dir_ / "small.png";
  const Result r = run_raypack("render --resolution 96x64 --spp 1 -o " + out.string());
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

TEST_F(Cli, RenderWritesTheSameExrBytesForOneAndTwoThreads) {
  const fs::path one = dir_ / "one.exr", two = dir_ / "two.exr";
  Result r = run_raypack("render --resolution 40x24 --spp 4 --seed 3 -q -t 1 -o " + one.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(r.output.empty()) << r.output;
  r = run_raypack("render --resolution 40x24 --spp 4 --seed 3 -q -t 2 -o " + two.string());
  ASSERT_EQ(r.status, 0) << r.output;
  const rp::Image img = rp::read_image(one.string());
  EXPECT_EQ(img.width, 40);
  EXPECT_EQ(img.height, 24);
  const std::string a = file_bytes(one), b = file_bytes(two);
  EXPECT_GT(a.size(), 1000u);
  EXPECT_TRUE(a == b) << "EXR files differ between 1 and 2 threads";
}

TEST_F(Cli, UnknownBackendIsAOneLineErrorWithStatusTwo) {
  const Result r = run_raypack("render --backend nope -o " + (dir_ / "x.png").string());
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.output, "raypack: --backend: unknown backend 'nope' (available: embree, simd)\n");
  EXPECT_FALSE(fs::exists(dir_ / "x.png"));
}

TEST_F(Cli, ABadBackendOrVariantNamesTheFlagGivenInEverySubcommand) {
  const std::pair<std::string, std::string> bad[] = {
      {"render --variant fastest",
       "--variant: 'fastest' is not a variant of embree (default, robust, compact, high, dynamic)"},
      {"trace --rays r.csv -o h.csv --backend nope", "--backend: unknown backend 'nope' (available: embree, simd)"},
      {"diff -b nope", "-b: unknown backend 'nope' (available: embree, simd)"},
      {"diff --variant-a watertight", "--variant-a: 'watertight' is not a variant of embree"},
      {"diff --variant-b robust",
       "--variant-b: 'robust' is not a variant of simd (default, median, watertight, spatial)"},
      {"stability --method simd/fast:stream", "--method: unknown method 'simd/fast:stream' (embree/default:packet8, "},
      {"stability --method simd/watertight", "--method: unknown method 'simd/watertight' ("},
      {"stability --family edgs", "--family: unknown family 'edgs' ("}};
  for (const auto& [args, message] : bad) {
    const Result r = run_raypack(args);
    EXPECT_EQ(r.status, 2) << args << ": " << r.output;
    EXPECT_EQ(r.output.rfind("raypack: " + message, 0), 0u) << args << ": " << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << args << ": " << r.output;
  }
}

TEST_F(Cli, MistypedSubcommandsAndFlagsGetTheNearestNameAndTheirOwnHelp) {
  const std::pair<std::string, std::string> cases[] = {
      {"rendr", "raypack: unknown subcommand 'rendr'; did you mean 'render'? (see raypack --help)\n"},
      {"frobnicate", "raypack: unknown subcommand 'frobnicate' (see raypack --help)\n"},
      {"render --scen x", "raypack: render: unknown flag '--scen'; did you mean --scene? (see raypack render --help)\n"},
      {"diff --variantb=x", "raypack: diff: unknown flag '--variantb'; did you mean --variant-b? (see raypack diff --help)\n"},
      {"stability --famly edges", "raypack: stability: unknown flag '--famly'; did you mean --family? (see raypack stability --help)\n"},
      {"render -x", "raypack: render: unknown flag '-x' (see raypack render --help)\n"},
      {"render --threads -1", "raypack: --threads: Value -1 not in range 0 to 1024 (see raypack render --help)\n"}};
  for (const auto& [args, message] : cases) {
    const Result r = run_raypack(args);
    EXPECT_EQ(r.status, 2) << args;
    EXPECT_EQ(r.output, message) << args;
  }
}

TEST_F(Cli, QuietPrintsNothingOnSuccessInEverySubcommand) {
  const fs::path rays = dir_ / "rays.csv", json = dir_ / "bench.json";
  std::ofstream(rays) << "ox,oy,oz,dx,dy,dz,tnear,tfar\n5,10,5,0,-1,0,0,inf\n";
  for (const std::string& args :
       {"render --resolution 8x8 -o " + (dir_ / "x.png").string(),
        "trace --rays " + rays.string() + " -o " + (dir_ / "hits.csv").string(), std::string("diff --count 64"),
        "bench --size 8 --min-runs 1 --max-runs 1 --kind primary --json " + json.string(),
        std::string("stability --count 8 --family edges --method embree/default:single")}) {
    const Result r = run_raypack(args + " -q");
    EXPECT_EQ(r.status, 0) << args << ": " << r.output;
    EXPECT_EQ(r.output, "") << args;
  }
  ASSERT_TRUE(fs::exists(json));
  const Result r = run_raypack("chart " + json.string() + " -o " + (dir_ / "c.png").string() + " -q");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(r.output, "");
  EXPECT_TRUE(fs::exists(dir_ / "c.png"));
}

TEST_F(Cli, BadFlagValuesAreOneLineErrorsWithStatusTwo) {
  for (const std::string args : {"render --resolution 10by10", "render --variant fastest", "render --backend simd --variant robust", "render --resolution 0x10",
                                 "render --resolution 100000x100000", "render --spp 0", "render --spp abc",
                                 "render --threads -1", "render --no-such-flag", "frobnicate", "render --up-axis w",
                                 "diff --up-axis 2", "bench --up-axis up"}) {
    const Result r = run_raypack(args + " -o " + (dir_ / "x.png").string());
    EXPECT_EQ(r.status, 2) << args << ": " << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << args << ": " << r.output;
    EXPECT_EQ(r.output.rfind("raypack: ", 0), 0u) << args << ": " << r.output;
  }
  EXPECT_FALSE(fs::exists(dir_ / "x.png"));
}

TEST_F(Cli, MissingSceneFileIsAnErrorWithStatusOne) {
  const fs::path scene = dir_ / "nope.obj";
  const Result r = run_raypack("render --scene " + scene.string() + " -o " + (dir_ / "x.png").string());
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_EQ(r.output, "raypack: " + scene.string() + ": cannot open: No such file or directory\n");
  EXPECT_FALSE(fs::exists(dir_ / "x.png"));
}

TEST_F(Cli, RendersAnObjFileWithTheSimdBackend) {
  const fs::path scene = dir_ / "quad.obj", out = dir_ / "quad.png";
  std::ofstream(scene) << "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3 4\n";
  const Result r =
      run_raypack("render --backend simd --scene " + scene.string() + " --resolution 32x32 -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("with simd/default"), std::string::npos) << r.output;
  const rp::Image img = rp::read_image(out.string());
  EXPECT_EQ(img.width, 32);
  EXPECT_EQ(img.height, 32);
}

TEST_F(Cli, AnOutputInAMissingFolderIsABadFlagAndNoFile) {
  const fs::path out = dir_ / "missing-dir" / "x.png";
  const Result r = run_raypack("render --resolution 16x16 -o " + out.string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_EQ(r.output, "raypack: -o: " + out.string() + ": cannot write: No such file or directory\n");
  EXPECT_NE(r.output.find(out.string()), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(Cli, TraceWritesOneHitPerRayAsTheBackendFindsThem) {
  const fs::path rays = dir_ / "rays.csv", hits = dir_ / "hits.csv", bin = dir_ / "hits.bin";
  // Down the y axis onto the default scene's ground plane (y = 0) from above, and one miss.
  std::ofstream(rays) << "ox,oy,oz,dx,dy,dz,tnear,tfar\n"
                      << "5,10,5,0,-1,0,0,inf\n"
                      << "5,10,5,0,1,0,0,inf\n";
  Result r = run_raypack("trace --rays " + rays.string() + " -o " + hits.string() + " --backend simd");
  ASSERT_EQ(r.status, 0) << r.output;
  std::ifstream in(hits);
  std::string header, first, second;
  std::getline(in, header);
  std::getline(in, first);
  std::getline(in, second);
  EXPECT_EQ(header, "t,prim_id,u,v,ng_x,ng_y,ng_z,instance_id");
  EXPECT_EQ(first.rfind("10,", 0), 0u) << first;  // t = 10 on the plane
  EXPECT_EQ(first.substr(first.size() - 9), ",0,1,0,-1") << first;  // normal +y, no instance
  EXPECT_EQ(second, "inf,-1,0,0,0,0,0,-1");
  r = run_raypack("trace --rays " + rays.string() + " -o " + bin.string() + " -q");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(fs::file_size(bin), 16u + 2u * 32u);
}

TEST_F(Cli, AFileNameWithAnUnknownExtensionIsABadFlagFoundBeforeAnyWork) {
  const fs::path rays = dir_ / "rays.csv";
  std::ofstream(rays) << "ox,oy,oz,dx,dy,dz\n5,10,5,0,-1,0\n";
  Result r = run_raypack("trace --rays " + rays.string() + " -o " + (dir_ / "hits.txt").string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_EQ(r.output, "raypack: -o: " + (dir_ / "hits.txt").string() +
                          ": unknown hit file extension '.txt' (.csv for text; .bin, .hits or none for binary)\n");
  EXPECT_FALSE(fs::exists(dir_ / "hits.txt"));
  for (const std::string& cmd : {"trace -o " + (dir_ / "h.bin").string() + " --rays", std::string("diff --rays"),
                                 std::string("bench --rays")}) {
    r = run_raypack(cmd + " " + (dir_ / "rays.json").string());
    EXPECT_EQ(r.status, 2) << cmd << ": " << r.output;
    EXPECT_EQ(r.output.rfind("raypack: --rays: " + (dir_ / "rays.json").string() + ": unknown ray file extension '.json'", 0), 0u)
        << cmd << ": " << r.output;
  }
}

TEST_F(Cli, TraceRejectsAMalformedRayFileWithStatusOne) {
  const fs::path rays = dir_ / "bad.csv";
  std::ofstream(rays) << "ox,oy,oz,dx,dy,dz,tnear,tfar\n1,2,3\n";
  const Result r = run_raypack("trace --rays " + rays.string() + " -o " + (dir_ / "h.csv").string());
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(r.output, "raypack: " + rays.string() + ": line 2: 3 values, expected 8\n");
  EXPECT_FALSE(fs::exists(dir_ / "h.csv"));
}

TEST_F(Cli, DiffPrintsTheTableWritesJsonAndAnImageAndHonoursMinAgreement) {
  const fs::path json = dir_ / "d.json", image = dir_ / "d.png";
  Result r = run_raypack("diff --kind primary --count 4096 -a embree -b simd --json " + json.string() + " --image " +
                         image.string() + " --min-agreement 99");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("\n4096 rays, embree/default (A) vs simd/default (B)"), std::string::npos) << r.output;
  for (const char* word : {"agree", "tie", "hit/miss", "wrong primitive", "t error", "reference supports"})
    EXPECT_NE(r.output.find(word), std::string::npos) << word << "\n" << r.output;
  EXPECT_NE(file_bytes(json).find("\"agreement\""), std::string::npos);
  EXPECT_EQ(rp::read_image(image.string()).width, 64);
  // A backend against the reference itself, demanding more agreement than float can give on
  // a scene with shared edges, must fail with status 3 when it falls short; 0 disagreements
  // would pass, so check the status matches the printed agreement.
  r = run_raypack("diff --kind random --count 20000 -a simd -b reference --min-agreement 100");
  const bool perfect = r.output.find("agreement 100.00000%") != std::string::npos;
  EXPECT_EQ(r.status, perfect ? 0 : 3) << r.output;
  r = run_raypack("diff --rays nowhere.rays");
  EXPECT_EQ(r.status, 1) << r.output;
  // --count is the number of rays traced, for every kind, not a rounded image size.
  for (const char* kind : {"primary", "diffuse", "random"}) {
    r = run_raypack(std::string("diff --count 100 --kind ") + kind);
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("\n100 rays, "), std::string::npos) << kind << ": " << r.output;
  }
  // --rays is a ray file in every command; generated rays are a --kind.
  r = run_raypack("diff --rays primary");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_EQ(r.output, "raypack: --rays: there is no ray file 'primary'; generated rays are chosen with --kind primary\n");
  r = run_raypack("diff --kind secondary");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_EQ(r.output, "raypack: --kind: 'secondary' is not primary, diffuse or random\n");
}

TEST_F(Cli, InfoCountsTheScene) {
  const fs::path scene = dir_ / "two.obj";
  // A quad (2 triangles), a degenerate triangle, and an unreferenced vertex.
  std::ofstream(scene) << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 5 5 5\nf 1 2 3 4\nf 1 2 2\n";
  const Result r = run_raypack("info " + scene.string());
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
  Result r = run_raypack("render --resolution 24x16 -q -o " + out.string() + " --aov " + aov.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_GT(fs::file_size(aov), 100u);
  r = run_raypack("render --resolution 24x16 -q -o " + out.string() + " --aov " + (dir_ / "aov.png").string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("AOVs are written as OpenEXR"), std::string::npos) << r.output;
}

TEST_F(Cli, EveryCameraAndSamplerRenders) {
  for (const std::string args : {"--camera panoramic", "--camera fisheye --fisheye-fov 200",
                                 "--camera thin-lens --aperture 0.2 --focus-distance 8 --spp 4",
                                 "--sampler uniform --spp 4", "--sampler random --spp 2", "--sampler adaptive",
                                 "--eye 0,2,9 --look-at 0,1,0 --up 0,1,0 --fov 50"}) {
    const fs::path out = dir_ / "c.png";
    const Result r = run_raypack("render --resolution 32x24 -o " + out.string() + " " + args);
    EXPECT_EQ(r.status, 0) << args << ": " << r.output;
    EXPECT_EQ(rp::read_image(out.string()).width, 32) << args;
  }
  for (const std::string args : {"--camera orthographic", "--sampler uniform --spp 3", "--eye 1,2", "--fov 200",
                                 "--eye 0,1,0 --look-at 0,1,0"}) {
    const Result r = run_raypack("render --resolution 32x24 -o " + (dir_ / "d.png").string() + " " + args);
    EXPECT_EQ(r.status, 2) << args << ": " << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << args << ": " << r.output;
  }
}

TEST_F(Cli, BenchWritesJsonAndChartsThatChartRedraws) {
  const fs::path json = dir_ / "b.json", chart = dir_ / "c.png", again = dir_ / "again.png";
  Result r =
      run_raypack("bench --size 16 --min-runs 1 --max-runs 2 --json " + json.string() + " --chart " + chart.string());
  ASSERT_EQ(r.status, 0) << r.output;
  for (const char* word : {"simd/default:large",
                           "simd/default:packet8",
                           "simd/default:single",
                           "embree/default:stream ",
                           "embree/default:packet8",
                           "embree/default:single",
                           "embree/robust:single",
                           "embree/default:stream-incoherent",
                           "simd/default:stream",
                           "simd/spatial:stream",
                           "simd/median:large",
                           "embree/high:single",
                           "bytes/prim",
                           "primary",
                           "shadow",
                           "diffuse",
                           "best simd",
                           "best embree",
                           "build: simd/default",
                           "fastest Embree"})
    EXPECT_NE(r.output.find(word), std::string::npos) << word << "\n" << r.output;
  const std::string text = file_bytes(json);
  for (const char* key : {"\"machine\"", "\"mrays_per_s\"", "\"mismatch_rate\"", "\"spread\"", "\"bytes_per_prim\"",
                          "\"build_seconds\"", "\"build_seconds_first\"", "\"build_runs\"", "\"commit\"", "\"compiler\"", "\"flags\"", "\"caches\"", "\"isa\"",
                          "\"coherent_method\"", "\"incoherent_method\"", "\"skipped_methods\""})
    EXPECT_NE(text.find(key), std::string::npos) << key;
  EXPECT_NE(text.find("\"version\": \"3."), std::string::npos) << "Embree's version recorded";
  for (const fs::path& p : {chart, dir_ / "c-scaling.png"})
    EXPECT_GT(fs::exists(p) ? fs::file_size(p) : 0u, 1000u) << p;
  EXPECT_FALSE(fs::exists(dir_ / "c.svg")) << "a .png chart is drawn as PNG only";
  EXPECT_EQ(rp::read_image(chart.string()).width, 3 * 500 + 280) << "three kinds' panels and the legend column";
  r = run_raypack("chart " + json.string() + " -o " + again.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(fs::exists(again));
  // The format follows the extension: an SVG named .svg, the PNG beside it untouched.
  const std::string png_bytes = file_bytes(chart);
  r = run_raypack("chart " + json.string() + " -o " + (dir_ / "c.svg").string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(file_bytes(dir_ / "c.svg").rfind("<?xml", 0), 0u);
  EXPECT_EQ(file_bytes(dir_ / "c-scaling.svg").rfind("<?xml", 0), 0u);
  EXPECT_EQ(file_bytes(chart), png_bytes);
  r = run_raypack("chart " + json.string() + " -o " + (dir_ / "c.jpg").string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("unknown chart format '.jpg'"), std::string::npos) << r.output;
  std::ofstream(dir_ / "bad.json") << "{\"not\": 1}";
  r = run_raypack("chart " + (dir_ / "bad.json").string() + " -o " + again.string());
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("bad.json: not a raypack bench file"), std::string::npos) << r.output;
  // Results of one ray kind, or of a ray file, chart as panels of those kinds only.
  const fs::path rays = dir_ / "rays.csv";
  std::ofstream(rays) << "ox,oy,oz,dx,dy,dz,tnear,tfar\n5,10,5,0,-1,0,0,inf\n5,10,5,0,1,0,0,inf\n";
  for (const std::string& args : {std::string("--kind primary"), "--rays " + rays.string()}) {
    fs::remove(chart);
    r = run_raypack("bench --size 8 --min-runs 1 --max-runs 1 --method 'simd/default:large' " + args + " --chart " +
                    chart.string());
    EXPECT_EQ(r.status, 0) << args << ": " << r.output;
    EXPECT_TRUE(fs::exists(chart)) << args;
  }
}

TEST_F(Cli, BenchFiltersMethodsAndKindsAndTimesRayFiles) {
  // --method and --kind choose the rows; every other method and kind is left out.
  Result r = run_raypack(
      "bench --size 16 --min-runs 1 --max-runs 1 --method '^embree/default:(stream|single)$' --kind shadow");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("embree/default:stream            shadow"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("embree/default:single            shadow"), std::string::npos) << r.output;
  for (const char* absent : {"simd", "packet8", "stream-incoherent", "robust", "primary ", "diffuse "})
    EXPECT_EQ(r.output.find(absent), std::string::npos) << absent << "\n" << r.output;
  // --rays times the file's rays, closest or any hit, and checks them against the reference.
  const fs::path rays = dir_ / "rays.csv";
  {
    std::ofstream out(rays);
    out << "ox,oy,oz,dx,dy,dz,tnear,tfar\n";
    for (int i = 0; i < 64; ++i) out << (i % 8) * 0.1 - 0.4 << "," << (i / 8) * 0.1 - 0.4 << ",5,0,0,-1,0,inf\n";
  }
  for (const std::string& flag : {std::string(), std::string(" --any-hit")}) {
    r = run_raypack("bench --min-runs 1 --max-runs 1 --method 'simd/default:large' --rays " + rays.string() + flag);
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find(flag.empty() ? "simd/default:large               file "
                                         : "simd/default:large               file-any"),
              std::string::npos)
        << r.output;
    EXPECT_NE(r.output.find("64 file"), std::string::npos) << r.output;
  }
  // Bad flags: one line naming the value, status 2 (a bad flag value or combination); a file
  // that cannot be read is a failure while running, status 1.
  const std::tuple<std::string, std::string, int> bad[] = {
      {"--method 'simd (' ", "--method 'simd (' is not a regular expression", 2},
      {"--method nothing-matches", "--method 'nothing-matches' matches none of: ", 2},
      {"--kind secondary", "--kind 'secondary' is not one of primary, shadow, diffuse", 2},
      {"--rays " + rays.string() + " --scene default --scene default", "--rays needs exactly one --scene", 2},
      {"--any-hit", "--any-hit applies to --rays only", 2},
      {"--rays " + (dir_ / "absent.bin").string(), "absent.bin", 1}};
  for (const auto& [args, message, status] : bad) {
    r = run_raypack("bench --size 8 --min-runs 1 --max-runs 1 " + args);
    EXPECT_EQ(r.status, status) << args;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << args << ": " << r.output;
    EXPECT_NE(r.output.find(message), std::string::npos) << args << ": " << r.output;
  }
}

TEST_F(Cli, HelpAndVersion) {
  Result r = run_raypack("--help");
  EXPECT_EQ(r.status, 0);
  EXPECT_NE(r.output.find("render"), std::string::npos);
  r = run_raypack("--version");
  EXPECT_EQ(r.status, 0);
  EXPECT_EQ(r.output.rfind("raypack ", 0), 0u) << r.output;
  r = run_raypack("backends");
  EXPECT_EQ(r.status, 0);
  EXPECT_NE(r.output.find("embree"), std::string::npos);
}

// ---- hostile input, round two -----------------------------------------------------------

TEST_F(Cli, CameraAndLightFlagsOutsideTheCoordinateRangeAreBadFlags) {
  const std::string out = " --resolution 16x16 -o " + (dir_ / "x.png").string();
  // Embree aborted the process (SIGABRT) on these before the range rule.
  Result r = run_raypack("render --eye 0,0,1e19 --look-at 0,0,0" + out);
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_EQ(r.output, "raypack: --eye: '0,0,1e19' is outside the supported coordinate range |x| <= 1073741824 (2^30)\n");
  r = run_raypack("render --eye 0,0,3e38" + out);
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_EQ(r.output.find("parallel"), std::string::npos) << r.output;
  r = run_raypack("render --camera thin-lens --eye 0,0,1e9 --aperture 1e9" + out);
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_EQ(r.output.rfind("raypack: --aperture: 1e+09 puts the lens around the eye", 0), 0u) << r.output;
  r = run_raypack("render --light 0,0,1e19,5" + out);
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_EQ(r.output.rfind("raypack: --light: '0,0,1e19,5' is outside the supported coordinate range", 0), 0u) << r.output;
  // A light is four numbers; the message says so whichever of them is wrong.
  for (const char* light : {"1,2,3", "1,2,x,4", "1,2,3,-1", "1,2,3,4,5"}) {
    r = run_raypack(std::string("render --light ") + light + out);
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_EQ(r.output, std::string("raypack: --light: '") + light + "' is not four numbers x,y,z,intensity with intensity > 0\n");
  }
  EXPECT_FALSE(fs::exists(dir_ / "x.png"));
}

TEST_F(Cli, AFileOutsideTheCoordinateRangeNamesTheFileAndLineNotTheCamera) {
  const fs::path scene = dir_ / "far.obj";
  std::ofstream(scene) << "v 1e38 0 0\nv 0 0 0\nv 0 1 0\nf 1 2 3\n";
  const std::string expected = "raypack: " + scene.string() +
                               ": line 1: vertex coordinate 1e38 is outside the supported coordinate range |x| <= "
                               "1073741824 (2^30)\n";
  for (const std::string& cmd : {"render -o " + (dir_ / "x.png").string(), std::string("diff --count 64"),
                                std::string("info")}) {
    const Result r = run_raypack(cmd + " --scene " + scene.string());
    EXPECT_EQ(r.status, 1) << cmd << ": " << r.output;
    EXPECT_EQ(r.output, expected) << cmd;
  }
}

TEST_F(Cli, RaysOutsideTheRangeAreTracedAsMissesWithAWarning) {
  const fs::path rays = dir_ / "rays.csv", hits = dir_ / "hits.csv";
  std::ofstream(rays) << "ox,oy,oz,dx,dy,dz,tnear,tfar\n"
                      << "0,1e19,0,0,-1,0,0,inf\n"      // Embree asserts on this origin
                      << "5,10,5,0,-1e19,0,0,inf\n"     // and on this direction
                      << "5,10,5,0,-1e-30,0,0,inf\n"    // too short to trace without overflow
                      << "5,10,5,0,-1,0,0,inf\n";       // an ordinary ray onto the ground plane
  for (const char* backend : {"embree", "simd"}) {
    const Result r =
        run_raypack(std::string("trace --backend ") + backend + " --rays " + rays.string() + " -o " + hits.string());
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("warning: " + rays.string() + ": 3 of 4 rays are outside the valid-ray rule"),
              std::string::npos)
        << r.output;
    const std::vector<rp::HitRecord> h = rp::read_hits(hits.string());
    ASSERT_EQ(h.size(), 4u);
    for (int i = 0; i < 3; ++i) EXPECT_EQ(h[i].prim_id, rp::kInvalidId) << backend << " ray " << i;
    EXPECT_EQ(h[3].t, 10.0f) << backend;
  }
  const Result r = run_raypack("diff --rays " + rays.string() + " -a embree -b simd --min-agreement 100");
  EXPECT_EQ(r.status, 0) << r.output;
}

TEST_F(Cli, OutputsNeverReplaceDevicesOrSymlinks) {
  const fs::path rays = dir_ / "rays.csv";
  std::ofstream(rays) << "ox,oy,oz,dx,dy,dz,tnear,tfar\n5,10,5,0,-1,0,0,inf\n";
  struct stat before {}, after {};
  ASSERT_EQ(::stat("/dev/null", &before), 0);
  Result r = run_raypack("trace --rays " + rays.string() + " -o /dev/null -q");
  EXPECT_EQ(r.status, 0) << r.output;
  ASSERT_EQ(::stat("/dev/null", &after), 0);
  EXPECT_TRUE(S_ISCHR(after.st_mode)) << "/dev/null was replaced";
  EXPECT_EQ(after.st_ino, before.st_ino);
  // Standard output on a pipe: the bytes arrive there.
  r = run_raypack("trace --rays " + rays.string() + " -o /dev/stdout -q");
  EXPECT_EQ(r.status, 0);
  EXPECT_EQ(r.output.size(), 16u + 32u);
  EXPECT_EQ(r.output.substr(0, 4), "RPHT");
  // A symlink stays a link; the file it names gets the image.
  fs::create_directory(dir_ / "store");
  std::ofstream(dir_ / "store" / "render.png") << "old";
  fs::create_symlink(dir_ / "store" / "render.png", dir_ / "latest.png");
  r = run_raypack("render --resolution 16x16 -q -o " + (dir_ / "latest.png").string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(fs::is_symlink(dir_ / "latest.png"));
  EXPECT_EQ(rp::read_image((dir_ / "store" / "render.png").string()).width, 16);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_ / "store"), fs::directory_iterator()), 1);
}

TEST_F(Cli, AnOutputWithoutAnImageWriterIsABadFlagThatLeavesNothing) {
  // OIIO has no writer for .xyz: refused with the flags, before an output file is opened.
  const Result r = run_raypack("render --resolution 16x16 -q -o " + (dir_ / "image.xyz").string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("no image writer for extension '.xyz'"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::is_empty(dir_)) << "left " << fs::directory_iterator(dir_)->path();
}

TEST_F(Cli, SpecialInputFilesAreRefusedAtOnce) {
  const fs::path fifo = dir_ / "x.obj";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  fs::create_symlink("/dev/zero", dir_ / "zero.ply");
  fs::create_symlink("/dev/zero", dir_ / "zero.bin");
  // `timeout` turns a hang (the old blocking open of a FIFO) into a failure, not a stuck suite.
  Result r = run_raypack("info " + fifo.string(), "timeout 20 ");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_EQ(r.output, "raypack: " + fifo.string() + ": cannot read: not a regular file (a FIFO)\n");
  r = run_raypack("info " + (dir_ / "zero.ply").string(), "timeout 20 ");
  EXPECT_EQ(r.output, "raypack: " + (dir_ / "zero.ply").string() + ": cannot read: not a regular file (a character device)\n");
  r = run_raypack("trace --rays " + (dir_ / "zero.bin").string() + " -o " + (dir_ / "h.bin").string(), "timeout 20 ");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("not a regular file (a character device)"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "h.bin"));
}

TEST_F(Cli, ParetoChartJoinsBenchAndStabilityByMethod) {
  const fs::path bench = dir_ / "b.json", stability = dir_ / "s.json", chart = dir_ / "c.svg";
  Result r = run_raypack(
      "stability --count 64 --family edges --family vertices --family translated --method simd/default:stream "
      "--method simd/watertight:stream --method embree/robust:single -q --json " +
      stability.string());
  ASSERT_EQ(r.status, 0) << r.output;
  r = run_raypack(
      "bench --size 8 --min-runs 1 --max-runs 1 --kind primary --kind diffuse --method "
      "'simd/(default|watertight):large|embree/(robust|default):packet8' -q --json " +
      bench.string() + " --chart " + chart.string() + " --stability " + stability.string());
  ASSERT_EQ(r.status, 0) << r.output;
  const std::string svg = file_bytes(dir_ / "c-pareto.svg");
  ASSERT_EQ(svg.rfind("<?xml", 0), 0u);
  // A point and a legend entry for each method in both files; embree/default is in the bench
  // only (embree/default:packet8), so it has neither.
  for (const char* method : {"simd/default", "simd/watertight", "embree/robust"})
    EXPECT_NE(svg.find(method), std::string::npos) << method;
  EXPECT_EQ(svg.find("embree/default"), std::string::npos);
  for (const char* panel : {"primary rays", "diffuse rays"}) EXPECT_NE(svg.find(panel), std::string::npos) << panel;
  EXPECT_EQ(svg.find("shadow rays"), std::string::npos) << "no panel for a kind not timed";
  // The redraw from the saved file gives the same picture.
  r = run_raypack("chart " + bench.string() + " -o " + (dir_ / "again.svg").string() + " --stability " +
                  stability.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(file_bytes(dir_ / "again-pareto.svg"), svg);
  EXPECT_EQ(r.output, "raypack: wrote " + (dir_ / "again.svg").string() + ", " + (dir_ / "again-scaling.svg").string() +
                          ", " + (dir_ / "again-pareto.svg").string() + "\n");
  // Files that cannot be joined: one-line errors naming the file, and no chart.
  const fs::path only_needles = dir_ / "needles.json";
  ASSERT_EQ(run_raypack("stability --count 16 --family needles -q --json " + only_needles.string()).status, 0);
  for (const auto& [file, message] :
       {std::pair{only_needles, ": no results of the families edges, vertices, translated 1e6, grazing"},
        std::pair{bench, ": not a raypack stability file (no \"results\")"}}) {
    r = run_raypack("chart " + bench.string() + " -o " + (dir_ / "bad.svg").string() + " --stability " + file.string());
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_EQ(r.output, "raypack: " + file.string() + message + "\n");
    EXPECT_FALSE(fs::exists(dir_ / "bad-pareto.svg"));
  }
  // A stability file whose methods the bench did not time.
  r = run_raypack(
      "bench --size 8 --min-runs 1 --max-runs 1 --kind primary --method 'embree/default:stream' -q --json " +
      (dir_ / "e.json").string());
  ASSERT_EQ(r.status, 0) << r.output;
  r = run_raypack("chart " + (dir_ / "e.json").string() + " -o " + (dir_ / "e.svg").string() + " --stability " +
                  stability.string());
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find(stability.string() + ": no method in common with the bench results"), std::string::npos)
      << r.output;
  // --stability draws a chart, so bench refuses it without --chart, and a bad file before timing.
  r = run_raypack("bench --size 8 --min-runs 1 --max-runs 1 --stability " + stability.string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("--stability: draws a chart, so it needs --chart"), std::string::npos) << r.output;
  r = run_raypack("bench --size 8 --min-runs 1 --max-runs 1 --chart " + (dir_ / "x.svg").string() + " --stability " +
                  only_needles.string());
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "x.svg"));
}

TEST_F(Cli, DeepJsonIsAOneLineError) {
  const fs::path scene = dir_ / "deep.json", bench = dir_ / "deep-bench.json";
  std::ofstream(scene) << "{\"objects\": " << std::string(70000, '[') << std::string(70000, ']') << "}";
  std::ofstream(bench) << std::string(70000, '{');
  Result r = run_raypack("render --scene " + scene.string() + " -o " + (dir_ / "x.png").string());
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_EQ(r.output, "raypack: " + scene.string() + ": line 1, column 76: nesting deeper than 64 levels\n");
  r = run_raypack("chart " + bench.string() + " -o " + (dir_ / "c.png").string());
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_EQ(r.output, "raypack: " + bench.string() + ": line 1, column 65: nesting deeper than 64 levels\n");
}

TEST_F(Cli, MessagesAreOneLineOfValidUtf8) {
  const fs::path scene = dir_ / "bad.json";
  // An unknown key with invalid UTF-8 and a newline and an escape sequence in it.
  std::ofstream(scene) << "{\"objects\": [], \"k\xff\xfe\\n\\u001b[31m\": 1}";
  Result r = run_raypack("render --scene " + scene.string());
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  EXPECT_EQ(rp::one_line(r.output.substr(0, r.output.size() - 1)), r.output.substr(0, r.output.size() - 1)) << r.output;
  // A syntax error whose "last read" text holds raw bytes.
  std::ofstream(scene) << "{\"objects\": [\xc3\x28\x1b]}";
  r = run_raypack("render --scene " + scene.string());
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  EXPECT_EQ(rp::one_line(r.output.substr(0, r.output.size() - 1)), r.output.substr(0, r.output.size() - 1)) << r.output;
}

TEST_F(Cli, ChartFileNamesAndLabelsAreDataNeverCommands) {
  const fs::path json = dir_ / "b.json";
  Result r = run_raypack("bench --size 8 --min-runs 1 --max-runs 1 --json " + json.string());
  ASSERT_EQ(r.status, 0) << r.output;
  // A name that closed gnuplot's quotes ran `system` through the old shell-and-script route.
  const fs::path odd = dir_ / "a'; system 'touch X'; x='.png";
  r = run_raypack("chart " + json.string() + " -o \"" + odd.string() + "\"");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(fs::exists(odd));
  EXPECT_FALSE(fs::exists(dir_ / "X"));
  EXPECT_FALSE(fs::exists("X"));
  // Scene names and method labels from the JSON file cannot break out of their strings.
  std::string text = file_bytes(json);
  const std::string evil_scene = "\"scene\": \"evil' . system('touch Y') . '\\nset output 'Z'\"";
  text.replace(text.find("\"scene\": \"default\""), std::string("\"scene\": \"default\"").size(), evil_scene);
  const size_t method = text.find("\"method\": \"");
  text.insert(method + 11, "m\\\"\\nEOD\\nsystem(\\\"touch W\\\")\\n");
  std::ofstream(dir_ / "evil.json") << text;
  r = run_raypack("chart " + (dir_ / "evil.json").string() + " -o " + (dir_ / "evil.svg").string());
  ASSERT_EQ(r.status, 0) << r.output;
  for (const char* made : {"Y", "Z", "W"}) EXPECT_FALSE(fs::exists(dir_ / made) || fs::exists(made)) << made;
  EXPECT_EQ(file_bytes(dir_ / "evil.svg").rfind("<?xml", 0), 0u);
  // Nothing temporary is left beside the charts.
  for (const auto& e : fs::directory_iterator(dir_))
    EXPECT_NE(e.path().filename().string().rfind(".raypack-", 0), 0u) << e.path();
}

TEST_F(Cli, InfoPrintsCountsAsIntegers) {
  const fs::path scene = dir_ / "grid.obj";
  std::ofstream f(scene);
  for (int y = 0; y <= 60; ++y)
    for (int x = 0; x <= 60; ++x) f << "v " << x << " " << y << " " << (x * y % 7) << "\n";
  for (int y = 0; y < 60; ++y)
    for (int x = 0; x < 60; ++x) f << "f " << y * 61 + x + 1 << " " << y * 61 + x + 2 << " " << (y + 1) * 61 + x + 2 << "\n";
  f.close();
  const Result r = run_raypack("info " + scene.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("prims=3600"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("e+"), std::string::npos) << r.output;
}

TEST_F(Cli, UpAxisIsXYOrZ) {
  const Result r = run_raypack("render --up-axis w -o " + (dir_ / "x.png").string());
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.output, "raypack: --up-axis: 'w' is not x, y or z\n");
  // A Z-up quad standing in the xz plane: with --up-axis z it faces the camera and fills the
  // middle of the picture; taken as Y up, the camera looks down at its edge and sees sky.
  const fs::path scene = dir_ / "standing.obj", out = dir_ / "standing.png";
  std::ofstream(scene) << "v -1 0 0\nv 1 0 0\nv 1 0 2\nv -1 0 2\nf 1 2 3 4\n";
  ASSERT_EQ(
      run_raypack("render --scene " + scene.string() + " --up-axis z --resolution 32x32 -q -o " + out.string()).status,
      0);
  const rp::Image z = rp::read_image(out.string());
  ASSERT_EQ(run_raypack("render --scene " + scene.string() + " --resolution 32x32 -q -o " + out.string()).status, 0);
  const rp::Image y = rp::read_image(out.string());
  const auto grey = [](const rp::Image& img, int x, int row) {  // the quad is grey, the sky bluish
    const float* p = &img.rgb[3 * size_t(row * img.width + x)];
    return std::abs(p[0] - p[2]) < 0.02f;
  };
  EXPECT_TRUE(grey(z, 16, 16));
  EXPECT_FALSE(grey(y, 16, 4));
}

TEST_F(Cli, RendersAndDescribesAGltfWithInstances) {
  const fs::path scene = dir_ / "scene.glb", out = dir_ / "gltf.png";
  rp::test::write_gltf(rp::test::hierarchy_gltf().model, scene.string(), rp::test::GltfForm::binary);
  Result r = run_raypack("render --backend simd --scene " + scene.string() + " --resolution 48x32 -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(rp::read_image(out.string()).width, 48);
  r = run_raypack("info " + scene.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("triangles    15 in 4 mesh(es)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("instances    3 placing 1 instanced mesh(es): 2 unique triangles, 6 instanced (placed) "
                          "triangles; 19 triangles in the world"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("top level     mesh level"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("instances=3"), std::string::npos) << r.output;
  // The simd mesh level's own tree: one instanced mesh of 2 triangles is one leaf under one node.
  EXPECT_NE(r.output.find("mesh_trees=1  mesh_prims=2  mesh_nodes=1  mesh_leaves=1  mesh_depth=1"), std::string::npos)
      << r.output;
}

TEST_F(Cli, OutOfMemoryNamesWhatWasBuiltAndTheBytes) {
  if (rp::test::kSanitized)
    GTEST_SKIP() << "AddressSanitizer reserves terabytes of address space, so `ulimit -v` cannot apply to it";
  const Result r =
      run_raypack("render --resolution 20000x10000 -q -o " + (dir_ / "x.png").string(), "ulimit -v 1500000; ");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_EQ(r.output.rfind("raypack: out of memory while rendering 20000x10000: an allocation of ", 0), 0u) << r.output;
  EXPECT_NE(r.output.find(" bytes failed\n"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "x.png"));
}

/// A bench file with one result, enough for `raypack chart` to draw both charts.
void write_small_bench_json(const fs::path& p) {
  std::ofstream(p) << R"({"machine": {"cpu": "test", "threads": 1, "date": "today"}, "scenes": [{"scene": "default",
    "triangles": 10, "results": [{"kind": "diffuse", "method": "simd x", "mrays_per_s": 1.5, "mismatch_rate": 0.001}]}]})";
}

// What a full disk does to a writer, without a full disk: a file-size limit (ulimit -f, in
// KiB blocks) makes every write past it fail as a full disk's does (EFBIG instead of ENOSPC),
// in raypack and in the gnuplot it starts; SIGXFSZ is ignored, as a full disk sends none.
TEST_F(Cli, AWriteThatFailsMidFileFailsTheCommandAndKeepsTheOldFile) {
  write_small_bench_json(dir_ / "b.json");
  std::ofstream(dir_ / "rays.csv") << "ox,oy,oz,dx,dy,dz\n";
  for (int i = 0; i < 200; ++i) std::ofstream(dir_ / "rays.csv", std::ios::app) << "5,10,5,0,-1,0\n";
  struct Case {
    std::string args, output;
    int limit = 2;  ///< KiB; 0 fails the first write (a chart of diff's classes is a few hundred bytes)
  };
  const std::string d = dir_.string() + "/";
  const Case cases[] = {
      {"render --resolution 256x256 -o " + d + "old.png", "old.png"},
      {"render --resolution 256x256 -o " + d + "old.exr", "old.exr"},
      {"render --resolution 256x256 -o " + d + "old.tif", "old.tif"},
      // The image fits under the limit; the AOVs do not.
      {"render --resolution 16x16 -o " + d + "small.png --aov " + d + "old-aov.exr", "old-aov.exr"},
      {"chart " + d + "b.json -o " + d + "old-chart.png", "old-chart.png"},
      {"chart " + d + "b.json -o " + d + "old-chart.svg", "old-chart.svg"},
      {"diff --kind primary --count 4096 --image " + d + "old-diff.png", "old-diff.png", 0},
      {"trace --rays " + d + "rays.csv -o " + d + "old-hits.csv", "old-hits.csv"},
  };
  for (const Case& c : cases) {
    std::ofstream(dir_ / c.output) << "the old file";
    const Result r = run_raypack(c.args + " -q", "trap '' XFSZ; ulimit -f " + std::to_string(c.limit) + "; ");
    EXPECT_EQ(r.status, 1) << c.args << ": " << r.output;
    EXPECT_NE(r.output.find(c.output + ": cannot write: File too large"), std::string::npos)
        << c.args << ": " << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << c.args << ": " << r.output;
    EXPECT_EQ(file_bytes(dir_ / c.output), "the old file") << c.args;
    for (const auto& e : fs::directory_iterator(dir_))
      EXPECT_EQ(e.path().filename().string().rfind(".raypack-", 0), std::string::npos)
          << c.args << " left " << e.path();
  }
  // The same commands without the limit write what they could not (the limit was the cause).
  const Result r = run_raypack("chart " + d + "b.json -q -o " + d + "old-chart.svg");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_GT(fs::file_size(dir_ / "old-chart.svg"), 2048u);
}

TEST_F(Cli, AnOutputThatIsAnInputOrAnotherOutputIsRefusedBeforeAnyWork) {
  const std::string d = dir_.string() + "/";
  std::ofstream(dir_ / "r.csv") << "ox,oy,oz,dx,dy,dz\n5,10,5,0,-1,0\n";
  std::ofstream(dir_ / "scene.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  write_small_bench_json(dir_ / "b.json");
  fs::create_symlink(dir_ / "r.csv", dir_ / "link.csv");
  fs::create_hard_link(dir_ / "r.csv", dir_ / "hard.csv");
  fs::create_directory(dir_ / "sub");
  struct Case {
    std::string args, message;
  };
  const Case cases[] = {
      {"trace --rays " + d + "r.csv -o " + d + "r.csv",
       "-o " + d + "r.csv: is the same file as the input --rays " + d + "r.csv"},
      {"trace --rays " + d + "r.csv -o " + d + "link.csv",
       "-o " + d + "link.csv: is the same file as the input --rays " + d + "r.csv"},
      {"trace --rays " + d + "r.csv -o " + d + "hard.csv",
       "-o " + d + "hard.csv: is the same file as the input --rays " + d + "r.csv"},
      {"trace --rays " + d + "r.csv -o " + d + "sub/../r.csv",
       "-o " + d + "sub/../r.csv: is the same file as the input --rays " + d + "r.csv"},
      {"trace --scene " + d + "scene.obj --rays " + d + "r.csv -o " + d + "scene.obj",
       "-o " + d + "scene.obj: is the same file as the input --scene " + d + "scene.obj"},
      {"bench --scene " + d + "scene.obj --json " + d + "scene.obj",
       "--json " + d + "scene.obj: is the same file as the input --scene " + d + "scene.obj"},
      // Two outputs that do not exist yet, by two names of one path.
      {"render -o " + d + "same.exr --aov " + d + "sub/../same.exr",
       "--aov " + d + "sub/../same.exr: is the same file as the output -o " + d + "same.exr"},
      {"diff --json " + d + "d.png --image " + d + "d.png",
       "--image " + d + "d.png: is the same file as the output --json " + d + "d.png"},
      {"chart " + d + "b.json -o " + d + "b.json",
       "-o " + d + "b.json: is the same file as the input json " + d + "b.json"},
      {"chart " + d + "b.json -o " + d + "c.png --stability " + d + "c-pareto.png",
       "-o (its -pareto chart) " + d + "c-pareto.png: is the same file as the input --stability " + d + "c-pareto.png"},
      {"stability --scene " + d + "scene.obj --json " + d + "scene.obj",
       "--json " + d + "scene.obj: is the same file as the input --scene " + d + "scene.obj"},
  };
  std::ofstream(dir_ / "c-pareto.png") << "stability";
  for (const Case& c : cases) {
    const std::string before =
        file_bytes(dir_ / "r.csv") + file_bytes(dir_ / "scene.obj") + file_bytes(dir_ / "b.json");
    const Result r = run_raypack(c.args);
    EXPECT_EQ(r.status, 2) << c.args << ": " << r.output;
    EXPECT_EQ(r.output, "raypack: " + c.message + "\n") << c.args;
    EXPECT_EQ(file_bytes(dir_ / "r.csv") + file_bytes(dir_ / "scene.obj") + file_bytes(dir_ / "b.json"), before)
        << c.args;
    EXPECT_FALSE(fs::exists(dir_ / "same.exr") || fs::exists(dir_ / "d.png")) << c.args;
  }
}

TEST_F(Cli, EveryOutputIsCheckedBeforeAnyWork) {
  // Each command would fail on its input (a scene that cannot be read): the output's message
  // comes first, with status 2, and no output is written.
  const std::string d = dir_.string() + "/", bad = " --scene " + d + "absent.obj";
  write_small_bench_json(dir_ / "b.json");
  fs::create_directory(dir_ / "c-scaling.png");
  struct Case {
    std::string args, message;
  };
  const Case cases[] = {
      {"render -o " + d + "x.foo" + bad, "-o: cannot write '" + d + "x.foo': no image writer for extension '.foo'"},
      {"render -o " + d + "x.sgi" + bad,
       "-o: cannot write '" + d + "x.sgi': the sgi writer cannot report a failed write"},
      {"render -o " + d + "x.png --aov " + d + "a.png" + bad,
       "--aov: cannot write AOVs to '" + d + "a.png': AOVs are written as OpenEXR (.exr)"},
      {"render -o " + d + "nowhere/x.png" + bad, "-o: " + d + "nowhere/x.png: cannot write: No such file or directory"},
      {"render -o " + d + "c-scaling.png" + bad, "-o: " + d + "c-scaling.png: cannot write: it is a directory"},
      {"diff --json " + d + "d.json --image " + d + "d.foo" + bad,
       "--image: cannot write '" + d + "d.foo': no image writer"},
      {"diff --json " + d + "nowhere/d.json" + bad,
       "--json: " + d + "nowhere/d.json: cannot write: No such file or directory"},
      {"trace --rays " + d + "absent.csv -o " + d + "nowhere/h.csv" + bad,
       "-o: " + d + "nowhere/h.csv: cannot write: No such file or directory"},
      {"chart " + d + "b.json -o " + d + "c.png",
       "-o (its -scaling chart): " + d + "c-scaling.png: cannot write: it is a directory"},
      {"bench --json " + d + "bench.json --chart " + d + "c.png" + bad,
       "--chart (its -scaling chart): " + d + "c-scaling.png: cannot write: it is a directory"},
      {"stability --json " + d + "s.json --chart " + d + "nowhere/s.svg" + bad,
       "--chart: " + d + "nowhere/s.svg: cannot write: No such file or directory"},
  };
  for (const Case& c : cases) {
    const Result r = run_raypack(c.args);
    EXPECT_EQ(r.status, 2) << c.args << ": " << r.output;
    EXPECT_EQ(r.output.rfind("raypack: " + c.message, 0), 0u) << c.args << ": " << r.output;
    for (const char* written : {"x.png", "d.json", "c.png", "bench.json", "s.json"})
      EXPECT_FALSE(fs::exists(dir_ / written)) << c.args << " wrote " << written;
  }
  for (const auto& e : fs::directory_iterator(dir_))
    EXPECT_EQ(e.path().filename().string().rfind(".raypack-", 0), std::string::npos) << "left " << e.path();
}


TEST_F(Cli, ATemporaryLeftByAKilledRunIsRemovedByTheNextOutputOfItsName) {
  std::ofstream(dir_ / "rays.csv") << "ox,oy,oz,dx,dy,dz\n5,10,5,0,-1,0\n";
  // What SIGKILL leaves: a temporary of h.csv from a process that is gone (a pid beyond any
  // pid_max). Kept: one of another name, one whose maker lives (this test, holding its lock),
  // and a file that only looks like one.
  const std::string gone = ".raypack-2147483000-0-h.csv", other = ".raypack-2147483000-0-other.csv",
                    live = ".raypack-" + std::to_string(::getpid()) + "-7-h.csv", odd = ".raypack-12x-0-h.csv";
  for (const std::string& name : {gone, other, live, odd}) std::ofstream(dir_ / name) << "partial";
  const int lock = ::open((dir_ / live).c_str(), O_RDONLY);
  ASSERT_EQ(::flock(lock, LOCK_EX), 0);
  const Result r = run_raypack("trace -q --rays " + (dir_ / "rays.csv").string() + " -o " + (dir_ / "h.csv").string());
  ::close(lock);
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(fs::exists(dir_ / "h.csv"));
  EXPECT_FALSE(fs::exists(dir_ / gone)) << "the stale temporary is still there";
  for (const std::string& name : {other, live, odd}) EXPECT_TRUE(fs::exists(dir_ / name)) << name << " was removed";
}


TEST_F(Cli, RunningOutOfMemoryWhileLoadingIsAlwaysTheOneLineMessage) {
  if (rp::test::kSanitized)
    GTEST_SKIP() << "AddressSanitizer reserves terabytes of address space, so `ulimit -v` cannot apply to it";
  // A JSON scene of 150,000 instances: under address-space limits from too small to enough,
  // every run either loads or fails with the one-line message (never std::terminate's abort,
  // once a failed allocation unwound into nlohmann::json's noexcept destructor).
  std::ofstream(dir_ / "tri.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  {
    std::ofstream out(dir_ / "many.json");
    out << R"({"meshes": {"tri": {"file": "tri.obj"}}, "objects": [)";
    for (int i = 0; i < 150000; ++i) out << (i ? "," : "") << R"({"type": "instance", "mesh": "tri"})";
    out << "]}";
  }
  int loaded = 0, refused = 0;
  for (int mib = 500; mib <= 1100; mib += 40) {
    const Result r = run_raypack("info --no-backends " + (dir_ / "many.json").string(),
                                 "ulimit -v " + std::to_string(mib * 1024) + "; ");
    if (r.status == 0) {
      ++loaded;
      continue;
    }
    ++refused;
    EXPECT_EQ(r.status, 1) << mib << " MiB: " << r.output;
    EXPECT_EQ(r.output.rfind("raypack: ", 0), 0u) << mib << " MiB: " << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << mib << " MiB: " << r.output;
    EXPECT_NE(r.output.find("out of memory"), std::string::npos) << mib << " MiB: " << r.output;
  }
  EXPECT_GT(refused, 0) << "no limit was small enough to matter";
  EXPECT_GT(loaded, 0) << "no limit was large enough to load";
}

}  // namespace
