// raypack across MPI ranks as a user runs it: mpirun -n 2 and -n 3 on this machine against
// one process with the same flags. Images (the frames of an animation among them), hit files,
// diff JSON and mismatch images must be the same bytes, exit statuses the same; a rank that fails or dies must end the
// run with one line and no output. Needs Open MPI's mpirun (kMpiexec, found by CMake).

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "io/rayfile.h"
#include "tests/support/animated_gltf.h"
#include "tests/support/build_paths.h"
#include "tests/support/sanitized.h"
#include "tests/support/shell.h"
#include "tests/support/temp_dir.h"

namespace {

namespace fs = std::filesystem;
using rp::test::TempDir;

using Result = rp::test::ShellResult;  // the output: every rank's and mpirun's
using rp::test::kSanitized;
using rp::test::run_shell;

const std::string kRaypack = rp::test::kRaypackExe;

/// The start of an mpirun command line: Open MPI's, quiet (no banners of its own), as root
/// when the tests run as root, more ranks than cores, no binding (ctest runs tests side by
/// side). Under LeakSanitizer the ranks skip leaks allocated by Open MPI's own libraries
/// (tests/mpi/openmpi-lsan.supp), without listing what was skipped.
std::string mpirun() {
  std::string env = "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 ";
  if (kSanitized)
    env += "LSAN_OPTIONS=suppressions=" + std::string(rp::test::kSourceDir) + "/tests/mpi/openmpi-lsan.supp" +
           ":print_suppressions=0 ";
  return env + rp::test::kMpiexec + " -q --oversubscribe --bind-to none";
}

/// run_shell for a command line with mpirun in it, without the lines Open MPI's event library
/// prints when its shutdown closes a descriptor its event loop still watches ("[warn] Epoll
/// MOD(1) on fd 26 failed. ...: Bad file descriptor"; open-mpi/ompi#5520, #2004): it broke a
/// comparison of outputs once in four runs of the suite under ASan on 2026-11-29.
Result mpi_shell(const std::string& command) {
  Result r = run_shell(command);
  static const std::string kWarn = "[warn] Epoll ";
  for (size_t at = r.output.find(kWarn); at != std::string::npos; at = r.output.find(kWarn, at)) {
    if (at > 0 && r.output[at - 1] != '\n') {
      at += kWarn.size();
      continue;
    }
    const size_t end = r.output.find('\n', at);
    r.output.erase(at, end == std::string::npos ? std::string::npos : end + 1 - at);
  }
  return r;
}

/// `raypack <args>` on `ranks` ranks.
Result ranks(int n, const std::string& args) { return mpi_shell(mpirun() + " -n " + std::to_string(n) + " " + kRaypack + " " + args); }

/// `raypack <args>` as one process, without mpirun.
Result one(const std::string& args) { return run_shell(kRaypack + " " + args); }

std::string bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// True when nothing in `dir` is a raypack temporary.
bool no_temporaries(const TempDir& dir) {
  for (const std::string& name : dir.entries())
    if (name.rfind(".raypack-", 0) == 0) return false;
  return true;
}

TEST(Mpi, RenderIsTheOneProcessImageForEverySamplerBackendAndRankCount) {
  TempDir tmp;
  // 70x50: 5x4 tiles, the last column and row partial.
  const std::string common = "render --resolution 70x50 --spp 2 --seed 5 -q";
  for (const std::string backend : {"embree", "simd"})
    for (const std::string sampler : {"stratified", "random"}) {
      const std::string args = common + " --backend " + backend + " --sampler " + sampler;
      const std::string want = tmp / "one.exr";
      Result r = one(args + " -o " + want);
      ASSERT_EQ(r.status, 0) << args << ": " << r.output;
      const bool both = (backend == "embree") == (sampler == "stratified");  // 3 ranks for two of the four
      for (int n : both ? std::vector<int>{2, 3} : std::vector<int>{2}) {
        const std::string got = tmp / ("ranks" + std::to_string(n) + ".exr");
        r = ranks(n, args + " -o " + got);
        ASSERT_EQ(r.status, 0) << n << " ranks, " << args << ": " << r.output;
        EXPECT_EQ(r.output, "") << args;
        EXPECT_EQ(bytes(got), bytes(want)) << n << " ranks, " << args;
      }
    }
  // Other cameras and the adaptive sampler, one tile per request (every tile a message).
  for (const std::string args :
       {"--backend simd --sampler adaptive --camera thin-lens --aperture 0.2 --focus-distance 8 --tiles-per-request 1",
        "--backend embree --camera fisheye --fisheye-fov 200 --spp 3 --sampler random"}) {
    const std::string want = tmp / "one.exr", got = tmp / "three.exr";
    ASSERT_EQ(one("render --resolution 50x34 -q " + args + " -o " + want).status, 0) << args;
    const Result r = ranks(3, "render --resolution 50x34 -q " + args + " -o " + got);
    ASSERT_EQ(r.status, 0) << args << ": " << r.output;
    EXPECT_EQ(bytes(got), bytes(want)) << args;
  }
  EXPECT_TRUE(no_temporaries(tmp));
}

TEST(Mpi, FramesAndPosesOfAnAnimationAreTheOneProcessOnes) {
  TempDir tmp;
  const std::string scene = tmp / "animated.gltf";
  rp::test::write_gltf(rp::test::animated_scene().model, scene, rp::test::GltfForm::embedded);
  // Frames 1 to 3, each rank posing its scene and updating its backend between them.
  for (const std::string backend : {"embree", "simd"}) {
    const std::string args =
        "render --resolution 48x32 -q --frames 1:3 --fps 8 --backend " + backend + " --scene " + scene;
    Result r = one(args + " -o " + tmp / "one-#.exr");
    ASSERT_EQ(r.status, 0) << r.output;
    r = ranks(2, args + " -o " + tmp / "two-#.exr");
    ASSERT_EQ(r.status, 0) << backend << ": " << r.output;
    for (const char* frame : {"1", "2", "3"}) {
      ASSERT_TRUE(fs::exists(tmp / ("two-" + std::string(frame) + ".exr"))) << frame;
      EXPECT_EQ(bytes(tmp / ("two-" + std::string(frame) + ".exr")),
                bytes(tmp / ("one-" + std::string(frame) + ".exr")))
          << backend << ", frame " << frame;
    }
  }
  // A trace at a time.
  rp::write_rays(tmp / "rays.bin", std::vector<rp::Ray>(999, rp::Ray{{0.3f, 0.2f, 5.0f}, 0.0f, {0, 0, -1}, INFINITY}));
  const std::string args = "trace --scene " + scene + " --time 0.3 --rays " + tmp / "rays.bin" + " -q -o ";
  ASSERT_EQ(one(args + tmp / "one.bin").status, 0);
  const Result r = ranks(3, args + tmp / "three.bin");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(bytes(tmp / "three.bin"), bytes(tmp / "one.bin"));
  EXPECT_TRUE(no_temporaries(tmp));
}

TEST(Mpi, RenderStatisticsCountEveryRank) {
  TempDir tmp;
  const std::string args = "render --resolution 64x48 --spp 1 --backend embree -o " + tmp / "x.png";
  const Result want = one(args), got = ranks(2, args);
  ASSERT_EQ(want.status, 0) << want.output;
  ASSERT_EQ(got.status, 0) << got.output;
  // The same rays, summed over the ranks; a line per rank with its tiles (12 in all).
  const auto line = [](const std::string& text, const std::string& start) {
    const size_t at = text.find(start);
    return at == std::string::npos ? std::string() : text.substr(at, text.find('\n', at) - at);
  };
  EXPECT_NE(got.output.find(" with embree/default on 2 ranks\n"), std::string::npos) << got.output;
  const std::string counts = line(want.output, " primary, ");
  EXPECT_FALSE(counts.empty()) << want.output;
  EXPECT_NE(got.output.find(counts), std::string::npos) << got.output;
  uint64_t tiles = 0;
  for (int k = 0; k < 2; ++k) {
    const std::string start = "raypack: rank " + std::to_string(k) + ": ";
    const std::string rank = line(got.output, start);
    ASSERT_FALSE(rank.empty()) << got.output;
    tiles += std::stoull(rank.substr(start.size()));
    EXPECT_NE(rank.find(" tiles in "), std::string::npos) << rank;
    if (k == 1) {
      EXPECT_NE(rank.find(" requests, waited "), std::string::npos) << rank;
    }
  }
  EXPECT_EQ(tiles, 12u) << got.output;
}

/// Rays at the default scene: hits, misses, rays outside the valid-ray rule.
std::vector<rp::Ray> test_rays(size_t n) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<rp::Ray> rays(n);
  for (size_t i = 0; i < n; ++i) {
    rays[i] = {{8 * u(rng), 4 + 4 * u(rng), 8 * u(rng)}, 0.0f, {u(rng), u(rng) - 0.4f, u(rng)},
               std::numeric_limits<float>::infinity()};
    if (i % 97 == 0) rays[i].dir = {0, 0, 0};  // invalid: a miss everywhere
  }
  return rays;
}

TEST(Mpi, TraceWritesTheOneProcessHitFileInEveryFormat) {
  TempDir tmp;
  const std::vector<rp::Ray> rays = test_rays(3001);  // shares of 1000 and 1001 rays: not whole packets
  rp::write_rays(tmp / "rays.bin", rays);
  rp::write_rays(tmp / "rays.csv", rays);
  struct Case {
    std::string in, out, coherence;
    std::vector<int> ranks;
  };
  for (const Case& c : {Case{"rays.bin", "hits.hits", "incoherent", {2, 3}}, Case{"rays.csv", "hits.csv", "incoherent", {2, 3}},
                        Case{"rays.bin", "hits.csv", "incoherent", {3}}, Case{"rays.csv", "hits.hits", "incoherent", {3}},
                        Case{"rays.bin", "hits.hits", "coherent", {3}}}) {
    const std::string args = "trace -q --backend simd --coherence " + c.coherence + " --rays " + tmp / c.in + " -o ";
    const Result want = one(args + tmp / ("one-" + c.out));
    ASSERT_EQ(want.status, 0) << want.output;
    for (int n : c.ranks) {
      const Result got = ranks(n, args + tmp / c.out);
      ASSERT_EQ(got.status, 0) << n << " ranks: " << got.output;
      EXPECT_EQ(got.output, "");
      EXPECT_EQ(bytes(tmp / c.out), bytes(tmp / ("one-" + c.out))) << c.in << " -> " << c.out << " " << c.coherence << ", " << n;
    }
  }
  // Standard input (read by rank 0, shared out) into standard output (written by rank 0).
  const Result want = run_shell("cat " + tmp / "rays.bin" + " | " + kRaypack + " trace -q --rays - -o /dev/stdout");
  const Result got = mpi_shell("cat " + tmp / "rays.bin" + " | " + mpirun() + " -n 3 " + kRaypack + " trace -q --rays - -o /dev/stdout");
  ASSERT_EQ(got.status, 0) << got.output.substr(0, 500);
  EXPECT_EQ(got.output.size(), 16 + 32 * rays.size());
  EXPECT_EQ(got.output, want.output);
  EXPECT_TRUE(no_temporaries(tmp));
}

TEST(Mpi, TraceQueriesWriteTheOneProcessFiles) {
  TempDir tmp;
  const std::vector<rp::Ray> rays = test_rays(3001);  // shares of 1000 and 1001 rays
  rp::write_rays(tmp / "rays.bin", rays);
  struct Case {
    std::string query, out;
    int ranks;
  };
  // The all-hits file's ray indices count the rays of the ranks before; its CSV lines differ
  // in length, its binary records are 40 bytes.
  for (const Case& c :
       {Case{"occluded", "q.bin", 2}, Case{"count", "q.csv", 3}, Case{"all", "q.csv", 2}, Case{"all", "q.bin", 3}}) {
    const std::string args = "trace -q --backend simd --query " + c.query + " --rays " + tmp / "rays.bin" + " -o ";
    const Result want = one(args + tmp / ("one-" + c.out));
    ASSERT_EQ(want.status, 0) << want.output;
    const Result got = ranks(c.ranks, args + tmp / c.out);
    ASSERT_EQ(got.status, 0) << c.query << ", " << c.ranks << " ranks: " << got.output;
    EXPECT_EQ(got.output, "");
    EXPECT_GT(bytes(tmp / c.out).size(), 3001u) << c.query;
    EXPECT_EQ(bytes(tmp / c.out), bytes(tmp / ("one-" + c.out))) << c.query << " -> " << c.out << ", " << c.ranks;
  }
  EXPECT_TRUE(no_temporaries(tmp));
}

TEST(Mpi, ABadRayFileGetsTheOneProcessMessageAndNoOutput) {
  TempDir tmp;
  std::string text = "ox,oy,oz,dx,dy,dz\n";
  for (int i = 0; i < 300; ++i) text += "1,2,3,0,-1,0\n";
  const std::string bad_late = text + "1,2,3,0,-1\n", blank_inside = text + "\n" + text.substr(18);
  for (const std::string& file : {bad_late, blank_inside}) {
    std::ofstream(tmp / "bad.csv") << file;
    const std::string args = "trace --rays " + tmp / "bad.csv" + " -o " + tmp / "h.csv";
    const Result want = one(args);
    ASSERT_EQ(want.status, 1) << want.output;
    // The same line, led by the rank whose share holds the bad line (not rank 0: the errors
    // are past the first share).
    const std::string message = want.output.substr(std::string("raypack: ").size());
    for (int n : {file == bad_late ? 3 : 2}) {
      const Result got = ranks(n, args);
      EXPECT_EQ(got.status, 1) << got.output;
      const std::string lead = "raypack: rank ";
      ASSERT_EQ(got.output.rfind(lead, 0), 0u) << got.output;
      const int rank = std::atoi(got.output.c_str() + lead.size());
      EXPECT_TRUE(rank >= 1 && rank < n) << got.output;
      EXPECT_EQ(got.output, lead + std::to_string(rank) + ": " + message);
    }
    EXPECT_FALSE(fs::exists(tmp / "h.csv"));
  }
  EXPECT_TRUE(no_temporaries(tmp));
}

TEST(Mpi, DiffGivesTheOneProcessJsonImageAndStatus) {
  TempDir tmp;
  rp::write_rays(tmp / "rays.bin", test_rays(2500));
  // A tight t tolerance, so that every class and both sides' error statistics have rays.
  const std::string common = "diff -q -a embree --t-tolerance 1e-7 --count 3000 ";
  const std::string b = "-b simd --variant-b watertight ";
  const std::vector<std::pair<std::string, std::vector<int>>> cases = {
      {b + "--kind primary --image IMAGE", {2, 3}}, {b + "--kind diffuse --image IMAGE", {3}}, {b + "--kind random", {2}},
      {b + "--rays " + tmp / "rays.bin", {3}}, {"--kind random -b reference --no-reference", {2}}};
  for (const auto& [rays, rank_counts] : cases) {
    const auto args = [&](const std::string& name) {
      std::string a = common + rays + " --json " + tmp / (name + ".json") + " --min-agreement 99.9";
      const size_t at = a.find("IMAGE");
      if (at != std::string::npos) a.replace(at, 5, tmp / (name + ".png"));
      return a;
    };
    const Result want = one(args("one"));
    ASSERT_TRUE(want.status == 0 || want.status == 3) << rays << ": " << want.output;
    for (int n : rank_counts) {
      const std::string name = "ranks" + std::to_string(n);
      const Result got = ranks(n, args(name));
      EXPECT_EQ(got.status, want.status) << n << " ranks, " << rays << ": " << got.output;
      EXPECT_EQ(got.output, want.output) << rays;
      EXPECT_EQ(bytes(tmp / (name + ".json")), bytes(tmp / "one.json")) << n << " ranks, " << rays;
      if (rays.find("IMAGE") != std::string::npos) {
        EXPECT_EQ(bytes(tmp / (name + ".png")), bytes(tmp / "one.png")) << n << " ranks, " << rays;
      }
    }
  }
  // What the ranks combined is not trivial: disagreements, and percentiles of many rays.
  ASSERT_EQ(one(common + b + "--kind primary --json " + tmp / "p.json").status, 0);
  const nlohmann::json j = nlohmann::json::parse(bytes(tmp / "p.json"));
  EXPECT_GT(j["classes"]["t error"]["count"].get<int>(), 0) << j.dump();
  EXPECT_GT(j["b_vs_reference"]["rays"].get<int>(), 1000) << j.dump();
  EXPECT_GT(j["b_vs_reference"]["t_rel_error_p99"].get<double>(), 0.0) << j.dump();
}

TEST(Mpi, ARankThatCannotReadTheSceneEndsTheRunWithOneLineAndNoOutput) {
  TempDir tmp;
  fs::create_directories(tmp / "here");
  fs::create_directories(tmp / "empty");
  std::ofstream(tmp / "here/scene.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  // The same command line on both ranks; rank 1 starts where there is no scene.obj.
  const std::string args = " render --scene scene.obj --resolution 32x32 -o " + tmp / "out.png";
  const Result r = mpi_shell(mpirun() + " -n 1 -wdir " + tmp / "here" + " " + kRaypack + args + " : -n 1 -wdir " +
                         tmp / "empty" + " " + kRaypack + args);
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_EQ(r.output, "raypack: rank 1: scene.obj: cannot open: No such file or directory\n");
  EXPECT_FALSE(fs::exists(tmp / "out.png"));
  EXPECT_TRUE(no_temporaries(tmp));
}

TEST(Mpi, ARankThatDiesEndsTheRunWithNoOutput) {
  TempDir tmp;
  // Rank 1 is killed (SIGKILL) mid-render: 4 s in (10 under the sanitizers, whose start is
  // slower), long before the render would end (a minute without the sanitizers); mpirun then
  // ends rank 0, which says why and removes what it had not finished.
  const std::string args = " render --resolution 1024x768 --spp 64 -t 1 -q -o " + tmp / "out.png";
  const std::string kill = " timeout -s KILL " + std::string(kSanitized ? "10 " : "4 ");
  const Result r = mpi_shell(mpirun() + " -n 1 " + kRaypack + args + " :" + " -n 1" + kill + kRaypack + args);
  EXPECT_NE(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("raypack: rank 0 stopped by SIGTERM: under mpirun, another rank died"), std::string::npos)
      << r.output;
  // Killed mid-render, before the image was begun: nothing was unfinished, and it says so.
  EXPECT_NE(r.output.find("; no output was left unfinished\n"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(tmp / "out.png"));
  EXPECT_TRUE(no_temporaries(tmp));
}

TEST(Mpi, ARankThatCannotWriteTheOutputEndsTheRunAtOnce) {
  TempDir tmp;
  fs::create_directories(tmp / "here/out");
  fs::create_directories(tmp / "there");
  std::ofstream(tmp / "rays.csv") << "ox,oy,oz,dx,dy,dz\n5,10,5,0,-1,0\n5,10,5,0,1,0\n";
  // Rank 1 runs where the output's folder does not exist (a node without the mount): every
  // rank checks the output before any work, and the run ends on both with rank 1's line.
  const std::string args = " trace --rays " + tmp / "rays.csv" + " -o out/h.bin";
  const Result r = mpi_shell("timeout 120 env " + mpirun() + " -n 1 -wdir " + tmp / "here" + " " + kRaypack + args +
                             " : -n 1 -wdir " + tmp / "there" + " " + kRaypack + args);
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_EQ(r.output, "raypack: rank 1: -o: out/h.bin: cannot write: No such file or directory\n");
  EXPECT_FALSE(fs::exists(tmp / "here/out/h.bin"));
  EXPECT_TRUE(fs::is_empty(tmp / "here/out"));
}

TEST(Mpi, RanksThatReadDifferentFilesUnderOnePathAreRefused) {
  TempDir tmp;
  for (const char* node : {"a", "b"}) fs::create_directories(tmp / node);
  // The same names on two "nodes": a scene that differs in one vertex, rays that differ in count.
  std::ofstream(tmp / "a/scene.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  std::ofstream(tmp / "b/scene.obj") << "v 0 0 0\nv 1 0 0\nv 0 1.5 0\nf 1 2 3\n";
  std::vector<rp::Ray> rays(1000, rp::Ray{{0.2f, 0.2f, 1.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, INFINITY});
  rp::write_rays(tmp / "a/rays.bin", rays);
  rays.resize(750);
  rp::write_rays(tmp / "b/rays.bin", rays);
  fs::copy_file(tmp / "a/scene.obj", tmp / "b/same.obj");
  fs::copy_file(tmp / "a/scene.obj", tmp / "a/same.obj");
  const auto on_two_nodes = [&](const std::string& args) {
    return mpi_shell(mpirun() + " -n 1 -wdir " + tmp / "a" + " " + kRaypack + " " + args + " : -n 1 -wdir " +
                     tmp / "b" + " " + kRaypack + " " + args);
  };
  const std::string differs = ": not what rank 0 read (another file under the same path on this rank's node?)\n";
  Result r = on_two_nodes("render --scene scene.obj --resolution 16x16 -o " + tmp / "x.png");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_EQ(r.output, "raypack: rank 1: --scene scene.obj" + differs);
  r = on_two_nodes("trace --scene same.obj --rays rays.bin -o " + tmp / "h.bin");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_EQ(r.output, "raypack: rank 1: --rays rays.bin" + differs);
  r = on_two_nodes("diff --scene scene.obj --count 64");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_EQ(r.output, "raypack: rank 1: --scene scene.obj" + differs);
  for (const char* out : {"x.png", "h.bin"}) EXPECT_FALSE(fs::exists(tmp / out)) << out;
  // The same files on both: the run goes on.
  r = on_two_nodes("trace --scene same.obj --rays " + tmp / "a/rays.bin" + " -q -o " + tmp / "h.bin");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(no_temporaries(tmp));
}

TEST(Mpi, RanksStartedWithOtherArgumentsAreRefused) {
  TempDir tmp;
  const Result r = mpi_shell(mpirun() + " -n 2 " + kRaypack + " render --spp 1 -o " + tmp / "x.png" + " : -n 1 " + kRaypack +
                         " render --spp 2 -o " + tmp / "x.png");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_EQ(r.output, "raypack: rank 2: started with other arguments than rank 0 (argument 3: '2' where rank 0 has '1'); "
                      "every rank must run the same raypack command\n");
  EXPECT_FALSE(fs::exists(tmp / "x.png"));
}

TEST(Mpi, CommandsThatRunInOneProcessAreRefusedAcrossRanksAndFlagErrorsPrintedOnce) {
  Result r = ranks(2, "bench --size 8");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_EQ(r.output, "raypack: bench runs in one process: start it without mpirun (render, trace and diff run across ranks)\n");
  r = ranks(3, "render --spp 0");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_EQ(r.output, one("render --spp 0").output);
  r = ranks(2, "render --measure-traces");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_EQ(r.output, "raypack: --measure-traces: times the traces of one process; start it without mpirun\n");
  r = ranks(2, "--version");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(r.output, one("--version").output);
}

}  // namespace
