#include "cli/info_cmd.h"

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>

#include "backends/registry.h"
#include "base/error.h"
#include "cli/args.h"

namespace rp::cli {

CLI::App* InfoArgs::add_to(CLI::App& app) {
  CLI::App* c = app.add_subcommand("info", "Counts, bounds and bytes of a scene and of each backend's structure");
  c->add_option("scene,--scene", scene, "Scene: 'default' or a scene file (.obj, .ply, .gltf, .glb, .json)")
      ->capture_default_str();
  add_time_option(c, time);
  c->add_flag("--no-backends", no_backends, "Skip building the backends");
  add_quiet_flag(c, quiet);
  return c;
}

/// Counts, bounds, degenerate triangles and the bytes of the scene and of each backend.
int run_info(const InfoArgs& a) {
  std::FILE* const out = a.quiet ? nullptr : stdout;  // -q: the scene and backends are still checked
  const std::optional<double> time = parse_time(a.time);
  const auto t0 = std::chrono::steady_clock::now();
  AnimatedScene animated = load_animated_scene_or_default(a.scene);
  pose(animated, time);
  const Scene& scene = animated.scene;
  const double load_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  size_t vertices = 0, with_normals = 0, with_uvs = 0;
  for (const MeshView& m : scene.meshes()) {
    vertices += m.positions.size();
    with_normals += !m.normals.empty();
    with_uvs += !m.uvs.empty();
  }
  const Box3f b = scene.bounds();
  say(out, "scene        %s (loaded in %.3f s)\n", a.scene.c_str(), load_s);
  say(out, "triangles    %u in %zu mesh(es), %zu vertices (%zu meshes with normals, %zu with uvs)\n",
      scene.triangle_count(), scene.meshes().size(), vertices, with_normals, with_uvs);
  if (!scene.instances().empty()) {
    size_t instanced_meshes = 0;
    uint64_t unique = 0;
    for (size_t m = 0; m < scene.meshes().size(); ++m)
      if (scene.is_instanced(m)) {
        ++instanced_meshes;
        unique += scene.meshes()[m].triangle_count();
      }
    say(out,
        "instances    %zu placing %zu instanced mesh(es): %llu unique triangles, %llu instanced (placed) "
        "triangles; %llu triangles in the world\n",
        scene.instances().size(), instanced_meshes, (unsigned long long)unique,
        (unsigned long long)scene.instanced_triangle_count(),
        (unsigned long long)(scene.triangle_count() - unique + scene.instanced_triangle_count()));
  }
  say(out, "analytic     %zu spheres, %zu quadrics, %zu polygons, %zu planes\n", scene.spheres().size(),
      scene.quadrics().size(), scene.polygons().size(), scene.planes().size());
  say(out, "primitives   %u\n", scene.prim_count());
  say(out, "degenerate   %zu zero-area triangles\n", scene.degenerate_triangle_count());
  if (b.empty())
    say(out, "bounds       empty\n");
  else
    say(out, "bounds       (%g, %g, %g) - (%g, %g, %g)\n", b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z);
  say(out, "materials    %zu; lights: %zu point, %zu directional; camera: %s\n", scene.materials().size(),
      scene.point_lights().size(), scene.directional_lights().size(),
      scene.camera() ? "from the scene" : "derived from the bounds");
  if (const SceneAnimation& anim = animated.animation; !anim.empty()) {
    const AnimationCounts& n = anim.counts();
    say(out, "animation    %zu animation(s), %zu channel(s) moving %zu node(s), %g s long; shown %s\n", n.animations,
        n.channels, n.nodes, anim.duration(), time ? cat("at ", *time, " s").c_str() : "at its rest pose");
  }
  const double prims = std::max(1.0, double(scene.prim_count()));
  say(out, "scene bytes  %zu (%.1f per primitive)\n", scene.bytes(), double(scene.bytes()) / prims);
  if (a.no_backends) return 0;
  // With instances, the bytes of each level: the top (the world's own structure and the one
  // over the instances) and the instanced meshes' structures, each built once.
  const bool levels = !scene.instances().empty();
  say(out, "\n%-8s %-10s %8s %14s %12s", "backend", "variant", "build s", "bytes", "bytes/prim");
  if (levels) say(out, " %14s %14s", "top level", "mesh level");
  say(out, "\n");
  for (const BackendEntry& e : list_backends()) {
    if (!e.available) {
      say(out, "%-8s unavailable: %s\n", e.name.c_str(), e.unavailable_reason.c_str());
      continue;
    }
    for (const std::string& variant : e.variants) {  // every variant: their memory differs (Embree's compact)
      const auto backend = build_backend(e.name, variant, scene, a.scene);
      const BackendInfo& i = backend->info();
      say(out, "%-8s %-10s %8.3f %14zu %12.1f", i.name.c_str(), i.variant.c_str(), i.build_seconds, i.bytes,
          double(i.bytes) / prims);
      if (levels) say(out, " %14zu %14zu", i.levels.top, i.levels.meshes);
      for (const auto& [key, value] : i.stats) {
        if (value == std::floor(value) && std::abs(value) < 9.0e15)  // counts as integers, never 1.99965e+07
          say(out, "  %s=%lld", key.c_str(), (long long)value);
        else
          say(out, "  %s=%g", key.c_str(), value);
      }
      say(out, "\n");
    }
  }
  return 0;
}

CLI::App* add_backends_command(CLI::App& app) {
  return app.add_subcommand("backends", "List the backends, their variants and availability");
}

int run_backends() {
  for (const BackendEntry& e : list_backends()) {
    std::string variants;
    for (const std::string& v : e.variants) variants += (variants.empty() ? "" : ", ") + v;
    std::string methods, incoherent, facts;
    for (const std::string& m : e.coherent_methods) methods += (methods.empty() ? "" : ", ") + m;
    for (const std::string& m : e.incoherent_methods) incoherent += (incoherent.empty() ? "" : ", ") + m;
    for (const auto& [k, v] : e.facts) facts += (facts.empty() ? "" : ", ") + k + "=" + v;
    std::printf("%-8s %s\n         variants: %s\n         coherent methods: %s\n         incoherent methods: %s\n"
                "         %s\n",
                e.name.c_str(), e.available ? e.description.c_str() : ("unavailable: " + e.unavailable_reason).c_str(),
                variants.c_str(), methods.c_str(), incoherent.c_str(), facts.c_str());
  }
  return 0;
}

}  // namespace rp::cli
