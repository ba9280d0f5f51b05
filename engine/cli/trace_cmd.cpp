#include "engine/cli/trace_cmd.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>

#include "engine/cli/args.h"
#include "engine/cli/out_of_memory.h"
#include "engine/rayfile.h"
#include "engine/analysis/raygen.h"
#include "engine/text.h"

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
  c->add_option("--rays", rays, "Ray file: .csv, or binary (.bin, .rays)")->required();
  c->add_option("-o,--output", output, "Hit file: .csv, or binary (.bin, .hits)")->required();
  add_backend_options(c, backend, variant);
  c->add_option("--coherence", coherence, "coherent (neighbouring rays as packets) or incoherent")->capture_default_str();
  add_threads_option(c, threads);
  add_quiet_flag(c, quiet);
  return c;
}

int run_trace(const TraceArgs& a) {
  check_method("--backend", a.backend, "--variant", a.variant);
  const Coherence coherence = parse_coherence("--coherence", a.coherence);
  check_file_name("--rays", a.rays, check_ray_file_name);
  check_file_name("-o", a.output, check_hit_file_name);
  const ThreadLimit limit(a.threads);
  const Scene scene = load_scene_or_default(a.scene);
  const std::vector<Ray> rays = with_memory_context("reading " + a.rays, [&] { return read_rays(a.rays); });
  const auto backend = build_backend(a.backend, a.variant, scene, a.scene);
  std::vector<Hit> hits;
  const auto start = std::chrono::steady_clock::now();
  with_memory_context(cat("tracing ", rays.size(), " rays"), [&] {
    hits.resize(rays.size());
    intersect_parallel(*backend, rays, hits, coherence);
  });
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  with_memory_context("writing " + a.output, [&] { write_hits(a.output, to_records(scene, rays, hits)); });
  if (!a.quiet) {
    const size_t n_hit = size_t(std::count_if(hits.begin(), hits.end(), [](const Hit& h) { return h.hit(); }));
    const size_t invalid = size_t(std::count_if(rays.begin(), rays.end(), [](const Ray& r) { return !valid_ray(r); }));
    std::fprintf(stderr, "raypack: traced %zu rays (%zu hits) with %s/%s in %.3f s (%.2f Mrays/s); wrote %s\n",
                 rays.size(), n_hit, a.backend.c_str(), a.variant.c_str(), seconds,
                 seconds > 0 ? double(rays.size()) / seconds * 1e-6 : 0.0, a.output.c_str());
    if (invalid > 0)
      warn(cat(a.rays, ": ", invalid, " of ", rays.size(), " rays are outside the valid-ray rule (finite, origin "
               "|x| <= 2^30, largest direction component in [2^-26, 2^31], 0 <= tnear <= tfar) and were "
               "reported as misses"));
  }
  return 0;
}

}  // namespace rp::cli
