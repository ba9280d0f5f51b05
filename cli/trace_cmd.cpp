#include "cli/trace_cmd.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <optional>

#include "analysis/raygen.h"
#include "base/text.h"
#include "cli/args.h"
#include "cli/out_of_memory.h"
#include "core/invalid_rays.h"
#include "io/rayfile.h"
#include "mpi/ray_parts.h"
#include "mpi/same_inputs.h"

namespace rp::cli {

namespace {

/// Hit records (with geometric normals) for writing to a hit file.
std::vector<HitRecord> to_records(const Scene& scene, std::span<const Ray> rays, std::span<const Hit> hits) {
  std::vector<HitRecord> out(hits.size());
  for (size_t i = 0; i < hits.size(); ++i)
    if (hits[i].hit())
      out[i] = {hits[i].t, hits[i].prim_id, hits[i].u, hits[i].v, scene.surface(rays[i], hits[i]).geometric_normal,
                hits[i].instance_id};
  return out;
}

}  // namespace

CLI::App* TraceArgs::add_to(CLI::App& app) {
  CLI::App* c = app.add_subcommand("trace", "Trace a ray file through a backend and write the hits");
  add_scene_option(c, scene);
  add_time_option(c, time);
  c->add_option("--rays", rays, "Ray file: .csv, or binary (.bin, .rays)")->required();
  c->add_option("-o,--output", output, "Hit file: .csv, or binary (.bin, .hits)")->required();
  add_backend_options(c, backend, variant);
  c->add_option("--coherence", coherence, "coherent (neighbouring rays as packets) or incoherent")->capture_default_str();
  add_threads_option(c, threads);
  add_quiet_flag(c, quiet);
  return c;
}

int run_trace(const TraceArgs& a, const dist::Comm& comm) {
  const bool across = comm.size() > 1, quiet = a.quiet || !comm.root();
  struct Flags {
    Coherence coherence;
    std::optional<double> time;
  };
  const Flags f = dist::together(comm, [&] {
    check_method("--backend", a.backend, "--variant", a.variant);
    const Flags flags{parse_coherence("--coherence", a.coherence), parse_time(a.time)};
    check_distinct_files({{"--scene", a.scene}, {"--rays", a.rays}}, {{"-o", a.output}});
    check_file_name("--rays", a.rays, check_ray_file_name);
    check_file_name("-o", a.output, check_hit_file_name);
    check_file_name("-o", a.output, check_output);  // every rank writes its share
    return flags;
  });
  const ThreadLimit limit(a.threads);
  // The scene as loaded, posed at --time before the backend is built.
  const AnimatedScene animated = dist::together(comm, [&] {
    AnimatedScene s = load_animated_scene_or_default(a.scene);
    pose(s, f.time);
    return s;
  });
  const Scene& scene = animated.scene;
  if (across) {  // each rank reads its own copies: they must be the same files
    std::vector<dist::InputDigest> inputs{{"--scene", a.scene, dist::scene_digest(scene)}};
    if (a.rays != "-")
      inputs.push_back(dist::together(comm, [&] {
        return dist::InputDigest{"--rays", a.rays, dist::file_digest(a.rays)};
      }));
    dist::check_same_inputs(comm, inputs);
  }
  // Across ranks each rank reads, traces and writes its share of the rays, in file order.
  const std::vector<Ray> rays =
      across ? dist::read_rays_across(comm, a.rays)
             : with_memory_context("reading " + a.rays, [&] { return read_rays(a.rays); });
  const auto backend = dist::together(comm, [&] { return build_backend(a.backend, a.variant, scene, a.scene); });
  std::vector<Hit> hits;
  const auto start = std::chrono::steady_clock::now();
  dist::together(comm, [&] {
    with_memory_context(cat("tracing ", rays.size(), " rays"), [&] {
      hits.resize(rays.size());
      intersect_parallel(*backend, rays, hits, f.coherence);
    });
  });
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const std::vector<HitRecord> records = dist::together(comm, [&] { return to_records(scene, rays, hits); });
  if (across)
    dist::write_hits_across(comm, a.output, records);
  else
    with_memory_context("writing " + a.output, [&] { write_hits(a.output, records); });
  uint64_t counts[] = {rays.size(), uint64_t(std::count_if(hits.begin(), hits.end(), [](const Hit& h) { return h.hit(); })),
                       uint64_t(std::count_if(rays.begin(), rays.end(), [](const Ray& r) { return !valid_ray(r); }))};
  comm.sum(counts);
  const std::vector<double> rank_seconds = dist::gather_each(comm, seconds);
  if (!quiet) {
    const uint64_t n = counts[0], n_hit = counts[1], invalid = counts[2];
    const double s = *std::max_element(rank_seconds.begin(), rank_seconds.end());
    std::fprintf(stderr, "raypack: traced %llu rays (%llu hits) with %s/%s in %.3f s (%.2f Mrays/s)%s; wrote %s\n",
                 (unsigned long long)n, (unsigned long long)n_hit, a.backend.c_str(), a.variant.c_str(), s,
                 s > 0 ? double(n) / s * 1e-6 : 0.0, across ? cat(" on ", comm.size(), " ranks").c_str() : "",
                 a.output.c_str());
    if (invalid > 0)
      warn(invalid_rays_message(a.rays, invalid, n));
  }
  return 0;
}

}  // namespace rp::cli
