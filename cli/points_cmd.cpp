#include "cli/points_cmd.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>

#include "base/text.h"
#include "cli/args.h"
#include "cli/out_of_memory.h"
#include "io/pointfile.h"

namespace rp::cli {

CLI::App* PointsArgs::add_to(CLI::App& app) {
  CLI::App* c = app.add_subcommand("points", "The closest surface point (and signed distance) to each point of a file");
  add_scene_option(c, scene)->required();
  add_time_option(c, time);
  c->add_option("--points", points, "Point file: .csv with columns x,y,z and optionally radius; - reads standard input")
      ->required();
  c->add_option("-o,--output", output, "Closest points: a .csv file")->required();
  add_backend_options(c, backend, variant);
  c->add_flag("--signed", with_sign, "Also the signed distance (negative inside) and whether each point is inside");
  add_threads_option(c, threads);
  add_quiet_flag(c, quiet);
  return c;
}

int run_points(const PointsArgs& a) {
  check_method("--backend", a.backend, "--variant", a.variant);
  const std::optional<double> time = parse_time(a.time);
  check_distinct_files({{"--scene", a.scene}, {"--points", a.points}}, {{"-o", a.output}});
  check_file_name("--points", a.points, check_point_file_name);
  check_file_name("-o", a.output, check_point_file_name);
  check_file_name("-o", a.output, check_output);
  const ThreadLimit limit(a.threads);
  AnimatedScene animated = load_animated_scene_or_default(a.scene);
  pose(animated, time);
  const Scene& scene = animated.scene;
  const std::vector<PointQuery> queries =
      with_memory_context("reading " + a.points, [&] { return read_points(a.points); });
  const auto backend = build_backend(a.backend, a.variant, scene, a.scene);
  // Asked once with no point, the backend refuses a scene it cannot answer (quadrics) even
  // when the file holds none.
  backend->closest_points({}, {});
  std::vector<ClosestPointRecord> records(queries.size());
  const auto start = std::chrono::steady_clock::now();
  with_memory_context(cat("finding the closest points of ", queries.size(), " points"), [&] {
    std::vector<ClosestPoint> closest(queries.size());
    for_each_chunk(queries.size(), [&](size_t begin, size_t n) {
      backend->closest_points(std::span(queries).subspan(begin, n), std::span(closest).subspan(begin, n));
    });
    std::vector<uint8_t> in;
    if (a.with_sign) {
      std::vector<Vec3f> points(queries.size());
      std::transform(queries.begin(), queries.end(), points.begin(), [](const PointQuery& q) { return q.point; });
      in.resize(points.size());
      inside(*backend, points, in);
    }
    for (size_t i = 0; i < queries.size(); ++i) {
      ClosestPointRecord& r = records[i];
      r.closest = closest[i];
      r.geometry_id = closest[i].found() ? scene.geometry_of(closest[i].prim_id) : kInvalidId;
      if (a.with_sign) {
        r.inside = in[i] != 0;
        r.signed_distance = r.inside ? -closest[i].distance : closest[i].distance;  // as rp::signed_distance
      }
    }
  });
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  with_memory_context("writing " + a.output, [&] { write_closest_points(a.output, records, a.with_sign); });
  if (!a.quiet) {
    const auto found = std::count_if(records.begin(), records.end(), [](const auto& r) { return r.closest.found(); });
    const auto inside_count = std::count_if(records.begin(), records.end(), [](const auto& r) { return r.inside; });
    std::fprintf(
        stderr, "raypack: %zu points (%zu with a surface point within their radius%s) with %s/%s in %.3f s; wrote %s\n",
        queries.size(), size_t(found), a.with_sign ? cat(", ", inside_count, " inside").c_str() : "", a.backend.c_str(),
        a.variant.c_str(), seconds, a.output.c_str());
  }
  return 0;
}

}  // namespace rp::cli
