// The queries beyond the closest hit from the command line (raypack trace --query, raypack
// points) against answers worked out here: the crossings of a sphere and a plane in closed
// form, the lists of every hit against their counts and the closest hits, both backends
// against each other, and a one-line error for each kind of bad input.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "tests/support/raypack_command.h"
#include "tests/support/temp_dir.h"

namespace {

namespace fs = std::filesystem;

using Result = rp::test::ShellResult;
using rp::test::file_bytes;
using rp::test::run_raypack;

constexpr double kInf = std::numeric_limits<double>::infinity();

/// A CSV file as text: the names of line 1 and the cells of every other line.
struct Table {
  std::vector<std::string> names;
  std::vector<std::vector<std::string>> rows;

  /// The column named `name` (a test failure and -1 when there is none).
  int column(const std::string& name) const {
    const auto it = std::find(names.begin(), names.end(), name);
    EXPECT_NE(it, names.end()) << "no column " << name;
    return it == names.end() ? -1 : int(it - names.begin());
  }
  double number(size_t row, const std::string& name) const {
    return std::strtod(rows[row][column(name)].c_str(), nullptr);
  }
  long long integer(size_t row, const std::string& name) const {
    return std::strtoll(rows[row][column(name)].c_str(), nullptr, 10);
  }
};

std::vector<std::string> cells(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream in(line);
  for (std::string cell; std::getline(in, cell, ',');) out.push_back(cell);
  return out;
}

Table read_table(const fs::path& p) {
  Table t;
  std::ifstream in(p);
  std::string line;
  if (!std::getline(in, line)) return t;
  t.names = cells(line);
  while (std::getline(in, line)) t.rows.push_back(cells(line));
  return t;
}

/// A ray as a ray file's CSV line holds it, in double.
struct RayText {
  double o[3], d[3], tnear = 0, tfar = kInf;
};

void write_rays(const fs::path& p, const std::vector<RayText>& rays) {
  std::ofstream out(p);
  out.precision(9);
  out << "ox,oy,oz,dx,dy,dz,tnear,tfar\n";
  for (const RayText& r : rays)
    out << float(r.o[0]) << ',' << float(r.o[1]) << ',' << float(r.o[2]) << ',' << float(r.d[0]) << ',' << float(r.d[1])
        << ',' << float(r.d[2]) << ',' << float(r.tnear) << ',' << (std::isinf(r.tfar) ? "inf" : std::to_string(r.tfar))
        << '\n';
}

/// The sphere and the plane of kBallScene.
constexpr double kCenter[3] = {0.25, 0.5, -0.5}, kRadius = 1.5, kFloor = -3.0;  // the plane y = kFloor

/// A sphere (prim 0) above a plane (prim 1), both analytic: their crossings have a closed form.
const char* const kBallScene = R"({"objects": [
  {"type": "sphere", "center": [0.25, 0.5, -0.5], "radius": 1.5},
  {"type": "plane", "normal": [0, 1, 0], "offset": -3}]})";

/// A hit worked out in double.
struct Crossing {
  double t;
  int prim;
};

/// Every crossing of the ray (o, d) (its float values) with kBallScene over [0, inf), by t.
std::vector<Crossing> crossings(const RayText& r) {
  double o[3], d[3];
  for (int k = 0; k < 3; ++k) o[k] = float(r.o[k]), d[k] = float(r.d[k]);
  std::vector<Crossing> out;
  // |o + t d - c|^2 = R^2: a t^2 + 2 b t + c = 0.
  double a = 0, b = 0, c = -kRadius * kRadius;
  for (int k = 0; k < 3; ++k) {
    const double oc = o[k] - kCenter[k];
    a += d[k] * d[k], b += oc * d[k], c += oc * oc;
  }
  const double disc = b * b - a * c;
  if (disc > 0) {
    for (const double t : {(-b - std::sqrt(disc)) / a, (-b + std::sqrt(disc)) / a})
      if (t >= 0) out.push_back({t, 0});
  }
  if (d[1] != 0) {
    const double t = (kFloor - o[1]) / d[1];
    if (t >= 0) out.push_back({t, 1});
  }
  std::sort(out.begin(), out.end(), [](const Crossing& x, const Crossing& y) { return x.t < y.t; });
  return out;
}

/// Rays at kBallScene from above and beside it, not normalized, none grazing the sphere; every
/// third ray's interval [tnear, tfar] ends or begins halfway between its first two crossings.
std::vector<RayText> ball_rays(int n) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<RayText> rays;
  while (int(rays.size()) < n) {
    RayText r{{kCenter[0] + 1.5 * u(rng), 4 + 2 * u(rng), kCenter[2] + 1.5 * u(rng)},
              {0.3 * u(rng), -1 + 0.3 * u(rng), 0.3 * u(rng)}};
    const double scale = 1.5 + u(rng);
    for (double& x : r.d) x *= scale;
    if (rays.size() % 5 == 4) r.d[1] = -r.d[1];  // away from both: no hit at all
    double a = 0, b = 0, c = -kRadius * kRadius;
    for (int k = 0; k < 3; ++k) {
      const double oc = r.o[k] - kCenter[k];
      a += r.d[k] * r.d[k], b += oc * r.d[k], c += oc * oc;
    }
    if (std::abs(b * b - a * c) < 0.05 * a) continue;  // near a tangent: the closed form is fragile
    const std::vector<Crossing> x = crossings(r);
    if (x.size() >= 2 && rays.size() % 3 == 1) r.tfar = (x[0].t + x[1].t) / 2;
    if (x.size() >= 2 && rays.size() % 3 == 2) r.tnear = (x[0].t + x[1].t) / 2;
    rays.push_back(r);
  }
  return rays;
}

class CliQueries : public ::testing::Test {
 protected:
  rp::test::TempDir tmp_;
  fs::path dir_ = tmp_.dir;

  /// `raypack <args>` that must succeed quietly.
  void run(const std::string& args) {
    const Result r = run_raypack(args + " -q");
    ASSERT_EQ(r.status, 0) << args << ": " << r.output;
    EXPECT_EQ(r.output, "") << args;
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
};

TEST_F(CliQueries, AllHitsAreEveryCrossingOfASphereAndAPlaneAtTheirClosedFormT) {
  std::ofstream(dir_ / "ball.json") << kBallScene;
  const std::vector<RayText> rays = ball_rays(300);
  write_rays(dir_ / "rays.csv", rays);
  std::string first_bytes;
  for (const std::string backend : {"simd", "embree"}) {
    SCOPED_TRACE(backend);
    run("trace --scene " + path("ball.json") + " --rays " + path("rays.csv") + " --query all --backend " + backend +
        " -o " + path("all.csv"));
    const Table all = read_table(dir_ / "all.csv");
    ASSERT_EQ(all.names,
              (std::vector<std::string>{"ray", "t", "prim_id", "u", "v", "ng_x", "ng_y", "ng_z", "instance_id"}));
    size_t row = 0, two_sphere_hits = 0, cut = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
      std::vector<Crossing> want;
      for (const Crossing& c : crossings(rays[i]))
        if (c.t >= rays[i].tnear && c.t <= rays[i].tfar) want.push_back(c);
      cut += want.size() < crossings(rays[i]).size();
      two_sphere_hits += std::count_if(want.begin(), want.end(), [](const Crossing& c) { return c.prim == 0; }) == 2;
      for (const Crossing& c : want) {
        ASSERT_LT(row, all.rows.size()) << "ray " << i << ": the list ends before its hit at t = " << c.t;
        ASSERT_EQ(all.integer(row, "ray"), long(i))
            << "row " << row << ": expected ray " << i << "'s hit at t = " << c.t;
        EXPECT_NEAR(all.number(row, "t"), c.t, 2e-6 * c.t) << "ray " << i << " row " << row;
        EXPECT_EQ(all.integer(row, "prim_id"), c.prim) << "ray " << i << " row " << row;
        EXPECT_EQ(all.integer(row, "instance_id"), -1);
        if (c.prim == 1) {
          EXPECT_EQ(all.number(row, "ng_y"), 1.0) << "the plane's normal, row " << row;
        }
        ++row;
      }
    }
    EXPECT_EQ(row, all.rows.size()) << "hits beyond the closed form's";
    EXPECT_GT(two_sphere_hits, 50u) << "rays through the sphere";
    EXPECT_GT(cut, 50u) << "rays whose interval leaves out a crossing";
    const std::string bytes = file_bytes(dir_ / "all.csv");
    if (first_bytes.empty())
      first_bytes = bytes;
    else
      EXPECT_TRUE(bytes == first_bytes) << "the backends' all-hits files differ";
  }
}

/// Rays from around the default scene (triangles, spheres, quadrics, a polygon, a plane) in
/// every direction, some with a finite tfar, some invalid.
void write_scene_rays(const fs::path& p, int n) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<RayText> rays(n);
  for (int i = 0; i < n; ++i) {
    RayText& r = rays[i];
    r = {{4 * u(rng), 2 + 2 * u(rng), 4 * u(rng)}, {u(rng), u(rng), u(rng)}};
    if (i % 4 == 1) r.tfar = 2 + 2 * u(rng);
    if (i % 4 == 2) r.tnear = 1 + u(rng);
    if (i % 97 == 0) r.d[0] = r.d[1] = r.d[2] = 0;  // invalid: no hit on any query
  }
  write_rays(p, rays);
}

TEST_F(CliQueries, CountsAreTheAllHitsListsLengthsAndOccludedIsWhetherAClosestHitExists) {
  const int n = 2000;
  write_scene_rays(dir_ / "rays.csv", n);
  std::map<std::string, std::string> first;  // query -> the first backend's file
  for (const std::string backend : {"simd", "embree"}) {
    SCOPED_TRACE(backend);
    for (const std::string q : {"closest", "occluded", "count", "all"})
      run("trace --rays " + path("rays.csv") + " --backend " + backend + " --query " + q + " -o " + path(q + ".csv"));
    const Table closest = read_table(dir_ / "closest.csv"), occluded = read_table(dir_ / "occluded.csv"),
                count = read_table(dir_ / "count.csv"), all = read_table(dir_ / "all.csv");
    ASSERT_EQ(occluded.names, std::vector<std::string>{"occluded"});
    ASSERT_EQ(count.names, std::vector<std::string>{"count"});
    ASSERT_EQ(closest.rows.size(), size_t(n));
    ASSERT_EQ(occluded.rows.size(), size_t(n));
    ASSERT_EQ(count.rows.size(), size_t(n));
    std::vector<size_t> listed(n), first_row(n, SIZE_MAX);
    long long last_ray = -1;
    double last_t = -kInf;
    for (size_t k = 0; k < all.rows.size(); ++k) {
      const long long ray = all.integer(k, "ray");
      const double t = all.number(k, "t");
      ASSERT_TRUE(ray >= 0 && ray < n) << "row " << k;
      ASSERT_TRUE(ray > last_ray || (ray == last_ray && t >= last_t)) << "row " << k << ": not sorted by ray, then t";
      if (ray != last_ray) first_row[ray] = k;
      last_ray = ray, last_t = t;
      ++listed[ray];
    }
    size_t hit = 0, several = 0;
    for (int i = 0; i < n; ++i) {
      const double t = closest.number(i, "t");
      EXPECT_EQ(count.integer(i, "count"), long(listed[i])) << "ray " << i;
      EXPECT_EQ(occluded.integer(i, "occluded"), std::isfinite(t) ? 1 : 0) << "ray " << i << ": closest t " << t;
      EXPECT_EQ(listed[i] > 0, std::isfinite(t)) << "ray " << i;
      if (listed[i] > 0) {
        EXPECT_NEAR(all.number(first_row[i], "t"), t, 1e-4 * t) << "ray " << i << ": the first of all";
      }
      hit += std::isfinite(t), several += listed[i] > 2;
    }
    EXPECT_GT(hit, size_t(n / 4));
    EXPECT_GT(several, size_t(n / 20)) << "rays through several surfaces";
    for (const std::string q : {"occluded", "count", "all"}) {
      const std::string bytes = file_bytes(dir_ / (q + ".csv"));
      if (!first.count(q))
        first[q] = bytes;
      else
        EXPECT_TRUE(bytes == first[q]) << q << ": the backends' files differ";
    }
  }
}

uint32_t u32_at(const std::string& b, size_t at) {
  uint32_t v = 0;
  std::memcpy(&v, b.data() + at, 4);
  return v;
}
uint64_t u64_at(const std::string& b, size_t at) {
  uint64_t v = 0;
  std::memcpy(&v, b.data() + at, 8);
  return v;
}
float f32_at(const std::string& b, size_t at) {
  float v = 0;
  std::memcpy(&v, b.data() + at, 4);
  return v;
}

TEST_F(CliQueries, BinaryQueryFilesHoldTheRecordsOfTheCsvFilesInTheDocumentedLayout) {
  write_scene_rays(dir_ / "rays.csv", 300);
  const std::string rays = " --rays " + path("rays.csv") + " --backend simd --query ";
  for (const std::string q : {"occluded", "count", "all"}) {
    run("trace" + rays + q + " -o " + path(q + ".csv"));
    run("trace" + rays + q + " -o " + path(q + ".bin"));
  }
  // occluded: 'RPOC', version 1, a byte per ray.
  std::string b = file_bytes(dir_ / "occluded.bin");
  const Table occluded = read_table(dir_ / "occluded.csv");
  ASSERT_EQ(b.size(), 16u + 300u);
  EXPECT_EQ(b.substr(0, 4), "RPOC");
  EXPECT_EQ(u32_at(b, 4), 1u);
  EXPECT_EQ(u64_at(b, 8), 300u);
  for (size_t i = 0; i < 300; ++i) EXPECT_EQ(long(b[16 + i]), occluded.integer(i, "occluded")) << i;
  // count: 'RPCN', version 1, a uint32 per ray.
  b = file_bytes(dir_ / "count.bin");
  const Table count = read_table(dir_ / "count.csv");
  ASSERT_EQ(b.size(), 16u + 4u * 300u);
  EXPECT_EQ(b.substr(0, 4), "RPCN");
  EXPECT_EQ(u32_at(b, 4), 1u);
  EXPECT_EQ(u64_at(b, 8), 300u);
  for (size_t i = 0; i < 300; ++i) EXPECT_EQ(long(u32_at(b, 16 + 4 * i)), count.integer(i, "count")) << i;
  // all: 'RPHA', version 1, 40 bytes per hit: uint64 ray, then a hit file's record.
  b = file_bytes(dir_ / "all.bin");
  const Table all = read_table(dir_ / "all.csv");
  ASSERT_GT(all.rows.size(), 100u);
  ASSERT_EQ(b.size(), 16u + 40u * all.rows.size());
  EXPECT_EQ(b.substr(0, 4), "RPHA");
  EXPECT_EQ(u32_at(b, 4), 1u);
  EXPECT_EQ(u64_at(b, 8), all.rows.size());
  const char* const floats[] = {"t", "", "u", "v", "ng_x", "ng_y", "ng_z"};
  for (size_t k = 0; k < all.rows.size(); ++k) {
    const size_t at = 16 + 40 * k;
    EXPECT_EQ(long(u64_at(b, at)), all.integer(k, "ray")) << k;
    EXPECT_EQ(int32_t(u32_at(b, at + 12)), all.integer(k, "prim_id")) << k;
    EXPECT_EQ(int32_t(u32_at(b, at + 36)), all.integer(k, "instance_id")) << k;
    for (int f = 0; f < 7; ++f) {
      if (!*floats[f]) continue;
      EXPECT_EQ(f32_at(b, at + 8 + 4 * f), std::strtof(all.rows[k][all.column(floats[f])].c_str(), nullptr)) << k;
    }
  }
}

TEST_F(CliQueries, TraceSaysWhatEachQueryFoundAndRefusesBadQueriesBeforeAnyWork) {
  std::ofstream(dir_ / "ball.json") << kBallScene;
  std::ofstream(dir_ / "rays.csv") << "ox,oy,oz,dx,dy,dz,tnear,tfar\n"
                                   << "0.25,5,-0.5,0,-1,0,0,inf\n"   // the sphere twice, the plane
                                   << "0.25,5,-0.5,0,1,0,0,inf\n"    // nothing
                                   << "0.25,5,-0.5,0,-1,0,0,3.6\n";  // the sphere's top only
  const std::string args = "trace --scene " + path("ball.json") + " --rays " + path("rays.csv") + " --backend simd ";
  const std::pair<std::string, std::string> found[] = {
      {"occluded", "(2 occluded)"}, {"count", "(4 hits)"}, {"all", "(4 hits)"}, {"closest", "(2 hits)"}};
  for (const auto& [q, what] : found) {
    const Result r = run_raypack(args + "--query " + q + " -o " + path(q + ".csv"));
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_EQ(r.output.rfind("raypack: traced 3 rays " + what + " with simd/default in ", 0), 0u) << r.output;
  }
  EXPECT_EQ(file_bytes(dir_ / "count.csv"), "count\n3\n0\n1\n");
  EXPECT_EQ(file_bytes(dir_ / "occluded.csv"), "occluded\n1\n0\n1\n");
  const std::pair<std::string, std::string> bad[] = {
      {"--query nearest", "raypack: --query: 'nearest' is not closest, occluded, count or all\n"},
      {"--query count --coherence coherent",
       "raypack: --coherence: coherent packets trace closest and occluded queries; --query count traces ray by ray\n"},
      {"--query all -o " + path("all.txt"),
       "raypack: -o: " + path("all.txt") +
           ": unknown hit file extension '.txt' (.csv for text; .bin, .hits or none for "
           "binary)\n"}};
  for (const auto& [flags, message] : bad) {
    const Result r =
        run_raypack(args + flags + (flags.find(" -o ") == std::string::npos ? " -o " + path("x.csv") : ""));
    EXPECT_EQ(r.status, 2) << flags;
    EXPECT_EQ(r.output, message) << flags;
  }
  EXPECT_FALSE(fs::exists(dir_ / "x.csv"));
  EXPECT_FALSE(fs::exists(dir_ / "all.txt"));
}

}  // namespace
