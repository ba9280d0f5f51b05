// raypack command line: `raypack render`, `raypack backends`. Only main() turns rp::Error
// into an exit status: 2 for bad flags or values, 1 for failures while running.

#include <tbb/global_control.h>
#include <tbb/info.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <iostream>
#include <optional>
#include <regex>

#include "backends/registry.h"
#include "engine/camera.h"
#include "engine/error.h"
#include "engine/image_io.h"
#include "engine/loaders/load.h"
#include "engine/render.h"
#include "engine/scene.h"

namespace {

/// A user error in the flags: reported like CLI11's own parse errors, exit status 2.
struct UsageError : rp::Error {
  using rp::Error::Error;
};

struct Resolution {
  int width, height;
};

constexpr int kMaxEdge = 32768;
constexpr long long kMaxPixels = 1ll << 28;

Resolution parse_resolution(const std::string& text) {
  static const std::regex re(R"(^\s*(\d{1,9})\s*[xX]\s*(\d{1,9})\s*$)");
  std::smatch m;
  if (!std::regex_match(text, m, re))
    throw UsageError(rp::cat("--resolution: '", text, "' is not WIDTHxHEIGHT (e.g. 1920x1080)"));
  const long long w = std::stoll(m[1]), h = std::stoll(m[2]);
  if (w < 1 || h < 1 || w > kMaxEdge || h > kMaxEdge || w * h > kMaxPixels)
    throw UsageError(rp::cat("--resolution: ", text, " is out of range (each side 1..", kMaxEdge, ", at most ",
                             kMaxPixels, " pixels)"));
  return {int(w), int(h)};
}

/// Unknown or unavailable backends and unknown variants are the user's mistake (status 2),
/// found before any scene is loaded.
void check_backend(const std::string& name, const std::string& variant) {
  std::string names;
  for (const rp::BackendEntry& e : rp::list_backends()) {
    names += (names.empty() ? "" : ", ") + e.name;
    if (e.name != name) continue;
    if (!e.available) throw UsageError(rp::cat("--backend: ", name, " is not available on this machine: ", e.unavailable_reason));
    std::string variants;
    for (const std::string& v : e.variants) {
      if (v == variant) return;
      variants += (variants.empty() ? "" : ", ") + v;
    }
    throw UsageError(rp::cat("--variant: '", variant, "' is not a variant of ", name, " (", variants, ")"));
  }
  throw UsageError(rp::cat("--backend: unknown backend '", name, "' (available: ", names, ")"));
}

struct RenderArgs {
  std::string scene = "default";
  std::string output = "raypack.png";
  std::string resolution = "1024x768";
  std::string backend{rp::kDefaultBackend};
  std::string variant = "default";
  int spp = 1;
  int threads = 0;
  uint64_t seed = 0;
  int max_depth = 3;
  bool quiet = false;
};

int run_render(const RenderArgs& a) {
  const Resolution res = parse_resolution(a.resolution);
  std::optional<tbb::global_control> limit;
  if (a.threads > 0) limit.emplace(tbb::global_control::max_allowed_parallelism, size_t(a.threads));

  check_backend(a.backend, a.variant);
  const rp::Scene scene = rp::load_scene(a.scene);
  const std::unique_ptr<rp::Backend> backend =
      rp::make_backend(a.backend, scene, {.variant = a.variant, .device_config = {}});
  const rp::PinholeCamera camera(scene.camera().value_or(rp::frame_bounds(scene.bounds())), res.width, res.height);
  rp::RenderSettings settings{res.width, res.height, a.spp, a.seed, a.max_depth};
  const rp::RenderResult r = rp::render(scene, *backend, camera, settings);
  rp::write_image(a.output, r.image);
  if (!a.quiet) {
    const rp::BackendInfo& info = backend->info();
    std::fprintf(stderr,
                 "raypack: wrote %s (%dx%d, %d spp) with %s/%s in %.3f s: %.2f Mrays/s "
                 "(%llu primary, %llu shadow, %llu reflection); build %.3f s, %.1f MiB\n",
                 a.output.c_str(), res.width, res.height, a.spp, info.name.c_str(), info.variant.c_str(),
                 r.stats.seconds, double(r.stats.rays()) / r.stats.seconds * 1e-6,
                 (unsigned long long)r.stats.primary, (unsigned long long)r.stats.shadow,
                 (unsigned long long)r.stats.reflection, info.build_seconds, double(info.bytes) / (1 << 20));
  }
  return 0;
}

int run_backends() {
  for (const rp::BackendEntry& e : rp::list_backends()) {
    std::string variants;
    for (const std::string& v : e.variants) variants += (variants.empty() ? "" : ", ") + v;
    std::printf("%-8s %s\n         variants: %s\n", e.name.c_str(),
                e.available ? e.description.c_str() : ("unavailable: " + e.unavailable_reason).c_str(),
                variants.c_str());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"raypack: 8-wide SIMD ray casting beside Intel Embree"};
  app.set_version_flag("--version", std::string("raypack ") + RAYPACK_VERSION);
  app.require_subcommand(1);

  RenderArgs ra;
  CLI::App* render = app.add_subcommand("render", "Render a scene (the embedded default or a file) to an image");
  render->add_option("--scene", ra.scene, "Scene: 'default' or an .obj/.ply file")->capture_default_str();
  render->add_option("-o,--output", ra.output, "Output image; format by extension (.png, .exr, ...)")
      ->capture_default_str();
  render->add_option("--resolution", ra.resolution, "Image size WIDTHxHEIGHT")->capture_default_str();
  render->add_option("--backend", ra.backend, "Backend name (see `raypack backends`)")->capture_default_str();
  render->add_option("--variant", ra.variant, "Backend variant (see `raypack backends`)")->capture_default_str();
  render->add_option("--spp", ra.spp, "Samples per pixel")->check(CLI::Range(1, 65536))->capture_default_str();
  render->add_option("-t,--threads", ra.threads, "Worker threads (0 = all cores)")
      ->check(CLI::Range(0, 1024))
      ->capture_default_str();
  render->add_option("--seed", ra.seed, "Seed of the per-pixel sample streams")->capture_default_str();
  render->add_option("--max-depth", ra.max_depth, "Mirror bounces after the primary hit")
      ->check(CLI::Range(0, 64))
      ->capture_default_str();
  render->add_flag("-q,--quiet", ra.quiet, "Print nothing on success");

  app.add_subcommand("backends", "List the backends, their variants and availability");

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "raypack: " << e.what() << " (see raypack --help)\n";
    return 2;
  }
  try {
    if (*render) return run_render(ra);
    return run_backends();
  } catch (const UsageError& e) {
    std::cerr << "raypack: " << e.what() << '\n';
    return 2;
  } catch (const rp::Error& e) {
    std::cerr << "raypack: " << e.what() << '\n';
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "raypack: internal error: " << e.what() << '\n';
    return 1;
  }
}
