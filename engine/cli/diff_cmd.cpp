#include "engine/cli/diff_cmd.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "engine/cli/args.h"
#include "engine/cli/out_of_memory.h"
#include "engine/analysis/diff.h"
#include "engine/render/image_io.h"
#include "engine/output_file.h"
#include "engine/rayfile.h"
#include "engine/analysis/raygen.h"
#include "engine/analysis/reference.h"

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

int run_diff(const DiffArgs& a) {
  if (a.a != "reference") check_method("-a", a.a, "--variant-a", a.variant_a);
  if (a.b != "reference") check_method("-b", a.b, "--variant-b", a.variant_b);
  const ThreadLimit limit(a.threads);
  if (a.count == 0 || a.count > (size_t(1) << 28))
    throw UsageError(cat("--count: ", a.count, " is out of range (1..", size_t(1) << 28, ")"));
  if (a.kind != "primary" && a.kind != "diffuse" && a.kind != "random")
    throw UsageError(cat("--kind: '", a.kind, "' is not primary, diffuse or random"));
  if ((a.rays == "primary" || a.rays == "diffuse" || a.rays == "random") && !std::filesystem::exists(a.rays))
    throw UsageError(cat("--rays: there is no ray file '", a.rays, "'; generated rays are chosen with --kind ", a.rays));
  if (!a.rays.empty()) check_file_name("--rays", a.rays, check_ray_file_name);
  const Scene scene = load_scene_or_default(a.scene, a.up_axis);
  const auto t0 = std::chrono::steady_clock::now();

  // The rays: a file, or generated. Camera rays keep their pixels for the mismatch image.
  RaySet set;
  Coherence coherence = Coherence::incoherent;
  if (!a.rays.empty()) {
    set.rays = with_memory_context("reading " + a.rays, [&] { return read_rays(a.rays); });
  } else if (a.kind == "primary" || a.kind == "diffuse") {
    // The smallest image of 4x2-pixel packets with at least --count pixels; primary rays are
    // its first --count rays.
    const int side = std::max(2, int(std::ceil(std::sqrt(double(a.count)))));
    const int w = (side + 3) / 4 * 4, h = (side + 1) / 2 * 2;
    set = primary_rays(scene, w, h);
    coherence = Coherence::coherent;
    if (a.kind == "primary") {
      set.rays.resize(a.count);
      set.pixel.resize(a.count);
    } else {
      // Bounces from the primary hits (found by the reference), as many rounds of one bounce
      // per hit as it takes to reach --count rays.
      const Reference reference(scene);
      std::vector<ReferenceHit> rh(set.rays.size());
      reference.intersect(set.rays, rh);
      std::vector<Hit> hits(set.rays.size());
      size_t n_hit = 0;
      for (size_t i = 0; i < rh.size(); ++i)
        if (rh[i].hit()) {
          hits[i] = to_hit(rh[i]);
          ++n_hit;
        }
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
      set = std::move(bounces);
      coherence = Coherence::incoherent;
    }
  } else {
    set = random_rays(scene, a.count, a.seed);
  }
  const std::string rays_label = a.rays.empty() ? a.kind : a.rays;
  if (!a.coherence.empty()) coherence = parse_coherence("--coherence", a.coherence);

  std::vector<ReferenceHit> ref;
  if (a.reference || a.a == "reference" || a.b == "reference") {
    const Reference reference(scene);
    ref.resize(set.rays.size());
    reference.intersect(set.rays, ref);
  }
  auto side = [&](const std::string& name, const std::string& variant) {
    DiffSide s{name == "reference" ? name : name + "/" + variant, std::vector<Hit>(set.rays.size())};
    if (name == "reference") {
      for (size_t i = 0; i < ref.size(); ++i) s.hits[i] = to_hit(ref[i]);
    } else {
      const auto backend = build_backend(name, variant, scene, a.scene);
      with_memory_context(cat("tracing ", set.rays.size(), " rays"),
                          [&] { intersect_parallel(*backend, set.rays, s.hits, coherence); });
    }
    return s;
  };
  const DiffSide sa = side(a.a, a.variant_a), sb = side(a.b, a.variant_b);
  const DiffOptions options{a.tie_tolerance, a.t_tolerance};
  const DiffResult d = diff_hits(scene, set.rays, sa.hits, sb.hits, a.reference ? std::span<const ReferenceHit>(ref) : std::span<const ReferenceHit>(), options);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  std::FILE* const out = a.quiet ? nullptr : stdout;
  say(out, "raypack diff: scene %s, rays %s%s, %s\n%s", a.scene.c_str(), rays_label.c_str(),
              a.reference ? ", reference: double-precision watertight" : "",
              coherence == Coherence::coherent ? "coherent (packets)" : "incoherent (single rays or streams)",
              format_table(d, sa.label, sb.label).c_str());
  say(out, "(%.2f s)\n", seconds);
  if (!a.json.empty()) {
    const std::string text = to_json(d, a.scene, rays_label, sa.label, sb.label, options);
    write_file(a.json, text);
  }
  if (!a.image.empty()) write_image(a.image, mismatch_image(d, set, sa.hits));
  if (100.0 * d.agreement() < a.min_agreement) {
    std::fprintf(stderr, "raypack: agreement %.5f%% is below --min-agreement %g%%\n", 100.0 * d.agreement(), a.min_agreement);
    return 3;
  }
  return 0;
}

}  // namespace rp::cli
