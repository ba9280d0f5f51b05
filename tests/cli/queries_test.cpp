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

/// A point of a point file, in double.
struct PointText {
  double p[3], radius = kInf;
};

void write_points(const fs::path& path, const std::vector<PointText>& points) {
  std::ofstream out(path);
  out.precision(9);
  out << "x,y,z,radius\n";
  for (const PointText& q : points)
    out << float(q.p[0]) << ',' << float(q.p[1]) << ',' << float(q.p[2]) << ','
        << (std::isinf(q.radius) ? "inf" : std::to_string(q.radius)) << '\n';
}

/// The closest point of kBallScene to `p` (its float values) worked out in double.
struct Nearest {
  double distance, point[3];
  int prim;
};

Nearest nearest_on_ball_scene(const PointText& q) {
  double p[3], to[3], r = 0;
  for (int k = 0; k < 3; ++k) p[k] = float(q.p[k]), to[k] = p[k] - kCenter[k], r += to[k] * to[k];
  r = std::sqrt(r);
  Nearest sphere{std::abs(r - kRadius), {}, 0}, plane{std::abs(p[1] - kFloor), {p[0], kFloor, p[2]}, 1};
  for (int k = 0; k < 3; ++k) sphere.point[k] = kCenter[k] + kRadius * to[k] / r;
  return sphere.distance <= plane.distance ? sphere : plane;
}

TEST_F(CliQueries, PointsAreAtTheirClosedFormDistancesFromASphereAndAPlane) {
  std::ofstream(dir_ / "ball.json") << kBallScene;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<PointText> points;
  while (points.size() < 400) {
    PointText q{{kCenter[0] + 4 * u(rng), 4 * u(rng), kCenter[2] + 4 * u(rng)}};
    double r = 0;
    for (int k = 0; k < 3; ++k) r += (q.p[k] - kCenter[k]) * (q.p[k] - kCenter[k]);
    const double to_sphere = std::abs(std::sqrt(r) - kRadius), to_plane = std::abs(q.p[1] - kFloor);
    if (std::sqrt(r) < 0.1 || std::abs(to_sphere - to_plane) < 1e-3) continue;  // the centre; a tie
    // Every third point's radius stops short of the surface, every third reaches past it.
    const double d = std::min(to_sphere, to_plane);
    if (points.size() % 3 == 1) q.radius = 0.5 * d;
    if (points.size() % 3 == 2) q.radius = 2 * d;
    points.push_back(q);
  }
  write_points(dir_ / "points.csv", points);
  std::string first;
  for (const std::string backend : {"simd", "embree"}) {
    SCOPED_TRACE(backend);
    run("points --scene " + path("ball.json") + " --points " + path("points.csv") + " --backend " + backend + " -o " +
        path("closest.csv"));
    const Table c = read_table(dir_ / "closest.csv");
    ASSERT_EQ(c.names,
              (std::vector<std::string>{"distance", "x", "y", "z", "prim_id", "geometry_id", "instance_id", "u", "v"}));
    ASSERT_EQ(c.rows.size(), points.size());
    size_t on_sphere = 0, on_plane = 0;
    for (size_t i = 0; i < points.size(); ++i) {
      const Nearest want = nearest_on_ball_scene(points[i]);
      if (i % 3 == 1) {  // nothing within the radius
        EXPECT_EQ(c.rows[i], (std::vector<std::string>{"inf", "nan", "nan", "nan", "-1", "-1", "-1", "0", "0"})) << i;
        continue;
      }
      EXPECT_NEAR(c.number(i, "distance"), want.distance, 1e-5 * (1 + want.distance)) << "point " << i;
      for (int k = 0; k < 3; ++k)
        EXPECT_NEAR(c.number(i, std::string(1, "xyz"[k])), want.point[k], 1e-5 * (1 + std::abs(want.point[k]))) << i;
      EXPECT_EQ(c.integer(i, "prim_id"), want.prim) << i;
      EXPECT_EQ(c.integer(i, "geometry_id"), want.prim) << i;  // one primitive per geometry here
      EXPECT_EQ(c.integer(i, "instance_id"), -1) << i;
      (want.prim == 0 ? on_sphere : on_plane)++;
    }
    EXPECT_GT(on_sphere, 50u);
    EXPECT_GT(on_plane, 50u);
    const std::string bytes = file_bytes(dir_ / "closest.csv");
    if (first.empty())
      first = bytes;
    else
      EXPECT_TRUE(bytes == first) << "the backends' closest points differ";
  }
  // The same points from standard input.
  const Result r =
      rp::test::run_shell("cat " + path("points.csv") + " | " + rp::test::kRaypackExe + " points --scene " +
                          path("ball.json") + " --points - -q -o " + path("stdin.csv"));
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(file_bytes(dir_ / "stdin.csv") == first);
}

TEST_F(CliQueries, SignedDistancesAreNegativeInsideASphereAndAClosedMesh) {
  // A sphere alone, and the closed cube [-1, 1]^3 as an OBJ of six quads.
  std::ofstream(dir_ / "sphere.json")
      << R"({"objects": [{"type": "sphere", "center": [0.25, 0.5, -0.5], "radius": 1.5}]})";
  std::ofstream(dir_ / "cube.obj")
      << "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n"
         "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
  const auto sphere_sdf = [](const double* p) {
    double r = 0;
    for (int k = 0; k < 3; ++k) r += (p[k] - kCenter[k]) * (p[k] - kCenter[k]);
    return std::sqrt(r) - kRadius;
  };
  const auto cube_sdf = [](const double* p) {  // the box's exact signed distance
    double out = 0, in = -kInf;
    for (int k = 0; k < 3; ++k) {
      const double q = std::abs(p[k]) - 1;
      out += std::max(q, 0.0) * std::max(q, 0.0), in = std::max(in, q);
    }
    return in > 0 ? std::sqrt(out) : in;
  };
  const std::pair<std::string, double (*)(const double*)> scenes[] = {{"sphere.json", +sphere_sdf},
                                                                      {"cube.obj", +cube_sdf}};
  for (const auto& [scene, sdf] : scenes) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-3, 3);
    std::vector<PointText> points;
    while (points.size() < 300) {
      PointText q{{u(rng), u(rng), u(rng)}};
      for (double& x : q.p) x = float(x);
      if (std::abs(sdf(q.p)) > 1e-2) points.push_back(q);  // not on the surface
    }
    write_points(dir_ / "points.csv", points);
    for (const std::string backend : {"simd", "embree"}) {
      SCOPED_TRACE(scene + ", " + backend);
      run("points --signed --scene " + path(scene) + " --points " + path("points.csv") + " --backend " + backend +
          " -o " + path("signed.csv"));
      const Table c = read_table(dir_ / "signed.csv");
      ASSERT_EQ(c.names.size(), 11u);
      EXPECT_EQ(c.names[9], "signed_distance");
      EXPECT_EQ(c.names[10], "inside");
      ASSERT_EQ(c.rows.size(), points.size());
      size_t inside = 0;
      for (size_t i = 0; i < points.size(); ++i) {
        const double want = sdf(points[i].p);
        EXPECT_NEAR(c.number(i, "signed_distance"), want, 1e-5 * (1 + std::abs(want))) << "point " << i;
        EXPECT_EQ(c.integer(i, "inside"), want < 0 ? 1 : 0) << "point " << i;
        EXPECT_EQ(c.number(i, "distance"), std::abs(c.number(i, "signed_distance"))) << i;
        inside += want < 0;
      }
      EXPECT_GT(inside, 10u);
    }
  }
}

TEST_F(CliQueries, BadPointFilesAreOneLineErrorsNamingTheFileTheLineAndTheValue) {
  std::ofstream(dir_ / "ball.json") << kBallScene;
  const std::string scene = " --scene " + path("ball.json"), out = path("out.csv"), bad = path("bad.csv");
  const std::pair<std::string, std::string> files[] = {
      {"x,y,z\n1,2,3\n1,2,abc\n", "line 3: 'abc' is not a number"},
      {"x,y,z\n1,2,3\n4,5\n", "line 3: 2 values, expected 3"},
      {"x,y,z,radius\n1,2,3,1,0\n", "line 2: 5 values, expected 4"},
      {"x,y,z\n1,nan,3\n", "line 2: y 'nan' is not a finite number"},
      {"x,y,z\n-inf,2,3\n", "line 2: x '-inf' is not a finite number"},
      {"x,y,z\n0,0,0\n1,2,2e9\n", "line 3: z '2e9' is outside the supported coordinate range |x| <= 1073741824 (2^30)"},
      {"radius,x,y,z\n-0.5,1,2,3\n", "line 2: radius '-0.5' is not a distance (a number >= 0, or inf)"},
      {"x,y,z,radius\n1,2,3,nan\n", "line 2: radius 'nan' is not a distance (a number >= 0, or inf)"},
      {"x,y\n1,2\n", "line 1: no column 'z' (columns: x,y,z,radius; all but radius are needed)"},
      {"x,y,z\n\n1,2,3\n", "line 2: blank line before the end of the data"}};
  for (const auto& [text, message] : files) {
    std::ofstream(bad) << text;
    const Result r = run_raypack("points" + scene + " --points " + bad + " -o " + out);
    EXPECT_EQ(r.status, 1) << text;
    EXPECT_EQ(r.output, "raypack: " + bad + ": " + message + "\n") << text;
    EXPECT_FALSE(fs::exists(out)) << text;
  }
  // Flags: exit status 2 before any work.
  std::ofstream(dir_ / "ok.csv") << "x,y,z\n0,3,0\n";
  const std::string ok = " --points " + path("ok.csv");
  const std::pair<std::string, std::string> flags[] = {
      {"points" + ok + " -o " + out, "raypack: --scene is required (see raypack points --help)\n"},
      {"points" + scene + " --points " + path("p.txt") + " -o " + out,
       "raypack: --points: " + path("p.txt") + ": unknown point file extension '.txt' (.csv: point files are text)\n"},
      {"points" + scene + ok + " -o " + path("out.bin"),
       "raypack: -o: " + path("out.bin") + ": unknown point file extension '.bin' (.csv: point files are text)\n"},
      {"points" + scene + ok + " -o " + path("ok.csv"),
       "raypack: -o " + path("ok.csv") + ": is the same file as the input --points " + path("ok.csv") + "\n"},
      {"points" + scene + ok + " -o " + out + " --backend simd --variant fast",
       "raypack: --variant: 'fast' is not a variant of simd (default, median, watertight, spatial)\n"}};
  for (const auto& [args, message] : flags) {
    const Result r = run_raypack(args);
    EXPECT_EQ(r.status, 2) << args;
    EXPECT_EQ(r.output, message) << args;
  }
  // A scene with quadrics: the backend's refusal, even for a file without points.
  std::ofstream(dir_ / "none.csv") << "x,y,z\n";
  for (const std::string backend : {"simd", "embree"}) {
    const Result r =
        run_raypack("points --scene default --points " + path("none.csv") + " --backend " + backend + " -o " + out);
    EXPECT_EQ(r.status, 1) << backend;
    EXPECT_EQ(r.output, "raypack: " + backend +
                            ": closest points: the scene has 6 quadrics (quadrics have no closest-point "
                            "routine)\n");
  }
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
