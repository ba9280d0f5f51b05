#include "cli/diff_cmd.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>

#include "analysis/diff.h"
#include "analysis/raygen.h"
#include "analysis/reference.h"
#include "cli/args.h"
#include "cli/out_of_memory.h"
#include "io/output_file.h"
#include "io/rayfile.h"
#include "mpi/diff_ranks.h"
#include "mpi/ray_parts.h"
#include "mpi/same_inputs.h"
#include "render/image_io.h"

namespace rp::cli {

namespace {

/// A side of the diff: a backend by name, or the reference itself.
struct DiffSide {
  std::string label;
  std::vector<Hit> hits;
};

}  // namespace

CLI::App* DiffArgs::add_to(CLI::App& app) {
  CLI::App* c = app.add_subcommand("diff", "The same rays through backends A and B and the double-precision reference");
  add_scene_option(c, scene);
  add_up_axis_option(c, up_axis);
  add_time_option(c, time);
  CLI::Option* k = c->add_option("--kind", kind, "Generated rays: primary, diffuse or random")->capture_default_str();
  c->add_option("--rays", rays, "A ray file (.csv, or binary: .bin, .rays) instead of generated rays")->excludes(k);
  c->add_option("--count", count, "Generated rays (primary: the first COUNT of the smallest packet-aligned image)")
      ->capture_default_str();
  c->add_option("--seed", seed, "Seed of generated diffuse and random rays")->capture_default_str();
  c->add_option("-a", a, "Backend A, or 'reference'")->capture_default_str();
  c->add_option("-b", b, "Backend B, or 'reference'")->capture_default_str();
  c->add_option("--variant-a", variant_a, "Variant of A")->capture_default_str();
  c->add_option("--variant-b", variant_b, "Variant of B")->capture_default_str();
  c->add_option("--coherence", coherence, "coherent or incoherent (default: coherent for primary rays)");
  c->add_option("--tie-tolerance", tie_tolerance, "Relative t difference of a tie")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  c->add_option("--t-tolerance", t_tolerance, "Relative t difference allowed on the same primitive")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  c->add_flag("--reference,!--no-reference", reference, "Arbitrate with the double-precision reference")
      ->capture_default_str();
  c->add_option("--json", json, "Write the summary as JSON");
  c->add_option("--image", image, "Write the per-ray classes as an image (camera rays)");
  c->add_option("--min-agreement", min_agreement, "Exit with status 3 below this agreement, in percent")
      ->check(CLI::Range(0.0, 100.0));
  add_threads_option(c, threads);
  add_quiet_flag(c, quiet);
  return c;
}

int run_diff(const DiffArgs& a, const dist::Comm& comm) {
  const bool across = comm.size() > 1;
  dist::together(comm, [&] {
    if (a.a != "reference") check_method("-a", a.a, "--variant-a", a.variant_a);
    if (a.b != "reference") check_method("-b", a.b, "--variant-b", a.variant_b);
  });
  const ThreadLimit limit(a.threads);
  const std::optional<double> time = dist::together(comm, [&] {
    if (a.count == 0 || a.count > (size_t(1) << 28))
      throw UsageError(cat("--count: ", a.count, " is out of range (1..", size_t(1) << 28, ")"));
    if (a.kind != "primary" && a.kind != "diffuse" && a.kind != "random")
      throw UsageError(cat("--kind: '", a.kind, "' is not primary, diffuse or random"));
    if ((a.rays == "primary" || a.rays == "diffuse" || a.rays == "random") && !std::filesystem::exists(a.rays))
      throw UsageError(cat("--rays: there is no ray file '", a.rays, "'; generated rays are chosen with --kind ", a.rays));
    if (!a.rays.empty()) check_file_name("--rays", a.rays, check_ray_file_name);
    if (comm.root()) {  // rank 0 writes the outputs
      check_distinct_files({{"--scene", a.scene}, {"--rays", a.rays}}, {{"--json", a.json}, {"--image", a.image}});
      if (!a.json.empty()) check_file_name("--json", a.json, check_output);
      if (!a.image.empty()) check_file_name("--image", a.image, check_image_output);
    }
    return parse_time(a.time);
  });
  // The scene posed at --time, seen (without a camera of its own) from where its rest pose is.
  const AnimatedScene animated = dist::together(comm, [&] {
    AnimatedScene s = load_animated_scene_or_default(a.scene, a.up_axis);
    frame_rest_pose(s);
    pose(s, time);
    return s;
  });
  const Scene& scene = animated.scene;
  if (across) {  // each rank reads its own copies: they must be the same files
    std::vector<dist::InputDigest> inputs{{"--scene", a.scene, dist::scene_digest(scene)}};
    if (!a.rays.empty() && a.rays != "-")
      inputs.push_back(dist::together(comm, [&] {
        return dist::InputDigest{"--rays", a.rays, dist::file_digest(a.rays)};
      }));
    dist::check_same_inputs(comm, inputs);
  }
  const auto t0 = std::chrono::steady_clock::now();

  // The rays: a file, or generated. Camera rays keep their pixels for the mismatch image.
  // Across ranks each rank diffs its share: a file's share is all it reads; generated rays
  // are made whole on every rank (from one seeded stream), then shared out below.
  RaySet set;
  Coherence coherence = Coherence::incoherent;
  if (!a.rays.empty()) {
    set.rays = across ? dist::read_rays_across(comm, a.rays)
                      : with_memory_context("reading " + a.rays, [&] { return read_rays(a.rays); });
  } else if (a.kind == "primary" || a.kind == "diffuse") {
    // The smallest image of 4x2-pixel packets with at least --count pixels; primary rays are
    // its first --count rays.
    const int side = std::max(2, int(std::ceil(std::sqrt(double(a.count)))));
    const int w = (side + 3) / 4 * 4, h = (side + 1) / 2 * 2;
    set = dist::together(comm, [&] { return primary_rays(scene, w, h); });
    coherence = Coherence::coherent;
    if (a.kind == "primary") {
      set.rays.resize(a.count);
      set.pixel.resize(a.count);
    } else {
      // Bounces from the primary hits (found by the reference), as many rounds of one bounce
      // per hit as it takes to reach --count rays.
      const std::vector<Hit> hits = dist::reference_hits_across(comm, scene, set.rays);
      set = dist::together(comm, [&] {
        const size_t n_hit = size_t(std::count_if(hits.begin(), hits.end(), [](const Hit& h) { return h.hit(); }));
        if (n_hit == 0) throw Error(cat(a.scene, ": no camera ray hits the scene, so there are no diffuse rays"));
        RaySet bounces;
        for (uint64_t round = 0; bounces.rays.size() < a.count; ++round) {
          const RaySet more = diffuse_rays(scene, set, hits, a.seed + round);
          bounces.rays.insert(bounces.rays.end(), more.rays.begin(), more.rays.end());
          bounces.pixel.insert(bounces.pixel.end(), more.pixel.begin(), more.pixel.end());
        }
        bounces.rays.resize(a.count);
        bounces.pixel.resize(a.count);
        bounces.width = set.width;
        bounces.height = set.height;
        return bounces;
      });
      coherence = Coherence::incoherent;
    }
  } else {
    set = dist::together(comm, [&] { return random_rays(scene, a.count, a.seed); });
  }
  const std::string rays_label = a.rays.empty() ? a.kind : a.rays;
  if (!a.coherence.empty()) coherence = dist::together(comm, [&] { return parse_coherence("--coherence", a.coherence); });
  // This rank's rays: its share of generated rays, all it read of a file.
  std::vector<Ray> shared_out;
  if (across && a.rays.empty()) {
    const RecordRange mine = dist::share(comm, set.rays.size());
    shared_out.assign(set.rays.begin() + std::ptrdiff_t(mine.first), set.rays.begin() + std::ptrdiff_t(mine.last));
  }
  const std::span<const Ray> rays = across && a.rays.empty() ? std::span<const Ray>(shared_out) : std::span<const Ray>(set.rays);

  std::vector<ReferenceHit> ref;
  if (a.reference || a.a == "reference" || a.b == "reference") {
    dist::together(comm, [&] {
      const Reference reference(scene);
      ref.resize(rays.size());
      reference.intersect(rays, ref);
    });
  }
  auto side = [&](const std::string& name, const std::string& variant) {
    DiffSide s{name == "reference" ? name : name + "/" + variant, std::vector<Hit>(rays.size())};
    if (name == "reference") {
      for (size_t i = 0; i < ref.size(); ++i) s.hits[i] = to_hit(ref[i]);
    } else {
      const auto backend = build_backend(name, variant, scene, a.scene);
      with_memory_context(cat("tracing ", rays.size(), " rays"),
                          [&] { intersect_parallel(*backend, rays, s.hits, coherence); });
    }
    return s;
  };
  const DiffSide sa = dist::together(comm, [&] { return side(a.a, a.variant_a); });
  const DiffSide sb = dist::together(comm, [&] { return side(a.b, a.variant_b); });
  const DiffOptions options{a.tie_tolerance, a.t_tolerance};
  DiffResult d = dist::together(comm, [&] {
    return diff_hits(scene, rays, sa.hits, sb.hits,
                     a.reference ? std::span<const ReferenceHit>(ref) : std::span<const ReferenceHit>(), options);
  });
  if (across) d = dist::combine_across(comm, std::move(d));
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  std::FILE* const out = a.quiet || !comm.root() ? nullptr : stdout;
  say(out, "raypack diff: scene %s, rays %s%s, %s\n%s", a.scene.c_str(), rays_label.c_str(),
              a.reference ? ", reference: double-precision watertight" : "",
              coherence == Coherence::coherent ? "coherent (packets)" : "incoherent (single rays or streams)",
              format_table(d, sa.label, sb.label).c_str());
  say(out, "(%.2f s)\n", seconds);
  if (!a.json.empty()) {
    dist::together(comm, [&] {
      if (comm.root()) write_file(a.json, to_json(d, a.scene, rays_label, sa.label, sb.label, options));
    });
  }
  if (!a.image.empty()) {
    // The image needs every ray's class and whether A hit: rank 0 gathers them.
    const std::vector<Hit> hits_a = dist::gather_vector(comm, std::span<const Hit>(sa.hits));
    d.per_ray = dist::gather_vector(comm, std::span<const DiffClass>(d.per_ray));
    dist::together(comm, [&] {
      if (comm.root()) write_image(a.image, mismatch_image(d, set, hits_a));
    });
  }
  if (100.0 * d.agreement() < a.min_agreement) {
    if (comm.root())
      std::fprintf(stderr, "raypack: agreement %.5f%% is below --min-agreement %g%%\n", 100.0 * d.agreement(),
                   a.min_agreement);
    return 3;
  }
  return 0;
}

}  // namespace rp::cli
