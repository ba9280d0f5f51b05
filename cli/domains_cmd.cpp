#include "cli/domains_cmd.h"

#include <CLI/CLI.hpp>
#include <cstdio>

#include "analysis/domains.h"
#include "analysis/raygen.h"
#include "cli/args.h"

namespace rp::cli {

namespace {

/// Bytes a data-parallel renderer sends to forward one ray: origin and direction (24), tnear
/// and tfar (8), its pixel (4), its path weight (12) and the closest hit so far, primitive and
/// barycentrics (12): 60, padded to 64.
constexpr int kRayMessageBytes = 64;

}  // namespace

CLI::App* DomainsArgs::add_to(CLI::App& app) {
  CLI::App* c = app.add_subcommand(
      "domains", "Simulate data-parallel ray tracing: the scene split into spatial domains, rays forwarded between owners");
  c->add_option("--scene", scene, "A scene file of triangle meshes (.obj, .ply, .gltf, .glb, .json)")->required();
  c->add_option("--domains", domains, "Domain counts to simulate (repeatable)")->check(CLI::Range(1, 4096))->capture_default_str();
  c->add_option("--size", size, "Camera rays: SIZE x SIZE pixels, their shadow rays and one diffuse bounce each")
      ->check(CLI::Range(1, 8192))
      ->capture_default_str();
  add_backend_options(c, backend, variant);
  c->add_option("--seed", seed, "Seed of the diffuse bounces")->capture_default_str();
  add_threads_option(c, threads);
  add_quiet_flag(c, quiet);
  return c;
}

int run_domains(const DomainsArgs& a) {
  std::FILE* const out = a.quiet ? nullptr : stdout;
  check_method("--backend", a.backend, "--variant", a.variant);
  const ThreadLimit limit(a.threads);
  const Scene scene = load_scene_or_default(a.scene);
  const auto whole = build_backend(a.backend, a.variant, scene, a.scene);
  // The rays: camera rays, and from their hits a shadow ray and a diffuse bounce each.
  const RaySet primary = primary_rays(scene, a.size, a.size);
  std::vector<Hit> hits(primary.rays.size());
  intersect_parallel(*whole, primary.rays, hits, Coherence::coherent);
  const RaySet shadow = shadow_rays(scene, primary, hits), diffuse = diffuse_rays(scene, primary, hits, a.seed);
  say(out,
      "raypack domains: %s, %u triangles (%zu scene bytes); %dx%d camera rays, a shadow ray and a diffuse "
      "bounce from each hit; %s/%s in every domain; a forwarded ray is %d bytes\n",
      a.scene.c_str(), scene.triangle_count(), scene.bytes(), a.size, a.size, a.backend.c_str(), a.variant.c_str(),
      kRayMessageBytes);
  say(out, "%7s %11s %12s %-8s %9s %9s %9s %10s %10s %12s %5s %10s %6s\n", "domains", "replicated", "bytes/domain",
      "kind", "rays", "hits", "no domain", "one domain", "visits/ray", "forwards/ray", "max", "bytes/ray", "check");
  for (const int count : a.domains) {
    const Domains d = split_domains(scene, count);
    std::vector<std::unique_ptr<Backend>> backends;
    size_t bytes = 0;  // the largest domain's scene and structure
    for (const Scene& part : d.parts) {
      backends.push_back(build_backend(a.backend, a.variant, part, a.scene));
      bytes = std::max(bytes, part.bytes() + backends.back()->info().bytes);
    }
    for (const auto& [kind, rays, any] : {std::tuple{"primary", &primary, false}, std::tuple{"shadow", &shadow, true},
                                          std::tuple{"diffuse", &diffuse, false}}) {
      const Traffic t = follow_rays(d, backends, *whole, rays->rays, any);
      const double n = std::max<double>(1.0, double(t.rays));
      say(out, "%7d %10.1f%% %12zu %-8s %9llu %9llu %8.1f%% %9.1f%% %10.3f %12.3f %5llu %10.1f %6s\n", count,
          100.0 * (double(d.triangles) / double(scene.triangle_count()) - 1.0), bytes, kind, (unsigned long long)t.rays,
          (unsigned long long)t.hits, 100.0 * double(t.no_domain) / n, 100.0 * double(t.one_domain) / n,
          double(t.visits) / n, double(t.forwards) / n, (unsigned long long)t.max_visits,
          kRayMessageBytes * double(t.forwards) / n,
          t.disagreements == 0 ? "ok" : std::to_string(t.disagreements).c_str());
    }
  }
  return 0;
}

}  // namespace rp::cli
