// raypack command line: `raypack render`, `raypack backends`. Only main() turns rp::Error
// into an exit status: 2 for bad flags or values, 1 for failures while running.

#include <tbb/global_control.h>
#include <tbb/info.h>

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <optional>
#include <mutex>
#include <regex>

#include "backends/registry.h"
#include "engine/camera.h"
#include "engine/error.h"
#include "engine/image_io.h"
#include "engine/cli/bench_cmd.h"
#include "engine/cli/out_of_memory.h"
#include "engine/cli/plot.h"
#include "engine/cli/stability_cmd.h"
#include "engine/diff.h"
#include "engine/loaders/load.h"
#include "engine/output_file.h"
#include "engine/rayfile.h"
#include "engine/raygen.h"
#include "engine/reference.h"
#include "engine/render.h"
#include "engine/scene.h"
#include "engine/text.h"

namespace {

using rp::cli::with_memory_context;

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

/// The backend `name`/`variant` built over `scene` (loaded from `scene_name`), with an
/// out-of-memory failure named as such.
std::unique_ptr<rp::Backend> build_backend(const std::string& name, const std::string& variant, const rp::Scene& scene,
                                           const std::string& scene_name) {
  const std::string what =
      rp::cat("building the ", name, "/", variant, " structure of ", scene_name, " (", scene.prim_count(), " primitives)");
  try {
    return with_memory_context(what, [&] { return rp::make_backend(name, scene, {.variant = variant, .device_config = {}, .coherent_method = {}}); });
  } catch (const rp::Error& e) {
    if (std::string_view(e.what()).starts_with("out of memory")) throw;
    throw rp::Error(rp::cat(what, ": ", e.what()));
  }
}

/// "x,y,z" as a vector, or a usage error naming the flag.
rp::Vec3f parse_vec3(const std::string& flag, const std::string& text) {
  static const std::regex re(R"(^\s*([^,\s]+)\s*,\s*([^,\s]+)\s*,\s*([^,\s]+)\s*$)");
  std::smatch m;
  rp::Vec3f v;
  bool ok = std::regex_match(text, m, re);
  for (int k = 0; ok && k < 3; ++k) {
    try {
      size_t used = 0;
      v[k] = std::stof(m[k + 1].str(), &used);
      ok = used == size_t(m[k + 1].length()) && std::isfinite(v[k]);
    } catch (const std::exception&) {
      ok = false;
    }
  }
  if (!ok) throw UsageError(rp::cat(flag, ": '", text, "' is not three finite numbers x,y,z"));
  return v;
}

/// "x,y,z" as a point, which must lie in the coordinate range every backend traces (engine/ray.h).
rp::Vec3f parse_point(const std::string& flag, const std::string& text) {
  const rp::Vec3f p = parse_vec3(flag, text);
  if (!rp::in_coordinate_range(p))
    throw UsageError(rp::cat(flag, ": '", text, "' is outside the supported coordinate range |x| <= 1073741824 (2^30)"));
  return p;
}

/// Camera overrides on the command line; each one replaces the scene's value.
struct CameraArgs {
  std::string model, eye, look_at, up;
  float fov = 0, fisheye_fov = 0, aperture = -1, focus_distance = -1;

  rp::CameraDesc apply(rp::CameraDesc c) const {
    if (!model.empty()) {
      if (model == "pinhole") c.model = rp::CameraModel::pinhole;
      else if (model == "panoramic") c.model = rp::CameraModel::panoramic;
      else if (model == "fisheye") c.model = rp::CameraModel::fisheye;
      else if (model == "thin-lens") c.model = rp::CameraModel::thin_lens;
      else throw UsageError(rp::cat("--camera: '", model, "' is not pinhole, panoramic, fisheye or thin-lens"));
    }
    if (!eye.empty()) c.eye = parse_point("--eye", eye);
    if (!look_at.empty()) c.look_at = parse_point("--look-at", look_at);
    if (!up.empty()) c.up = parse_vec3("--up", up);
    if (fov > 0) c.vfov_degrees = fov;
    if (fisheye_fov > 0) c.fisheye_fov_degrees = fisheye_fov;
    if (aperture >= 0) c.aperture = aperture;
    if (focus_distance >= 0) c.focus_distance = focus_distance;
    if (aperture >= 0 && c.model == rp::CameraModel::thin_lens && !rp::in_coordinate_range(abs(c.eye) + rp::Vec3f(aperture)))
      throw UsageError(rp::cat("--aperture: ", aperture, " puts the lens around the eye (", c.eye.x, ", ", c.eye.y, ", ",
                               c.eye.z, ") outside the supported coordinate range |x| <= 1073741824 (2^30)"));
    return c;
  }

  void add_to(CLI::App* app) {
    app->add_option("--camera", model, "pinhole, panoramic, fisheye or thin-lens (default: the scene's)");
    app->add_option("--eye", eye, "Camera position x,y,z");
    app->add_option("--look-at", look_at, "Point the camera looks at x,y,z");
    app->add_option("--up", up, "Up vector x,y,z");
    app->add_option("--fov", fov, "Vertical field of view, degrees")->check(CLI::Range(0.001, 179.999));
    app->add_option("--fisheye-fov", fisheye_fov, "Fisheye field of view across the image circle, degrees")
        ->check(CLI::Range(0.001, 360.0));
    app->add_option("--aperture", aperture, "Thin lens radius, world units")->check(CLI::Range(0.0, 1073741824.0));
    app->add_option("--focus-distance", focus_distance, "Distance in focus (0: the look-at point)")
        ->check(CLI::Range(0.0, 2147483648.0));
  }

  /// True when any flag changes the scene's camera.
  bool any() const {
    return !model.empty() || !eye.empty() || !look_at.empty() || !up.empty() || fov > 0 || fisheye_fov > 0 ||
           aperture >= 0 || focus_distance >= 0;
  }
};

struct RenderArgs {
  CameraArgs camera;
  std::vector<std::string> lights;
  std::string aov;
  std::string sampler = "stratified";
  float adaptive_threshold = 0.05f;
  int adaptive_depth = 3;
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

rp::RenderSettings render_settings(const RenderArgs& a, const Resolution& res) {
  rp::RenderSettings settings;
  settings.width = res.width;
  settings.height = res.height;
  settings.spp = a.spp;
  settings.seed = a.seed;
  settings.max_depth = a.max_depth;
  settings.adaptive_threshold = a.adaptive_threshold;
  settings.adaptive_depth = a.adaptive_depth;
  if (a.sampler == "uniform") settings.sampler = rp::Sampler::uniform;
  else if (a.sampler == "random") settings.sampler = rp::Sampler::random;
  else if (a.sampler == "stratified") settings.sampler = rp::Sampler::stratified;
  else if (a.sampler == "adaptive") settings.sampler = rp::Sampler::adaptive;
  else throw UsageError(rp::cat("--sampler: '", a.sampler, "' is not uniform, random, stratified or adaptive"));
  const int m = int(std::sqrt(double(a.spp)));
  if (settings.sampler == rp::Sampler::uniform && m * m != a.spp)
    throw UsageError(rp::cat("--spp: ", a.spp, " is not a square, which the uniform sampler needs (1, 4, 9, ...)"));
  return settings;
}

/// A progress bar with the time left on stderr, for renders that last more than a second
/// and only when stderr is a terminal; redrawn at most 10 times a second.
class ProgressBar {
 public:
  ProgressBar() : start_(std::chrono::steady_clock::now()) {}
  void operator()(double fraction) {
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    if (elapsed < 1.0 || !::isatty(STDERR_FILENO)) return;
    std::unique_lock lock(mutex_, std::try_to_lock);
    if (!lock || (elapsed - last_ < 0.1 && fraction < 1.0)) return;
    last_ = elapsed;
    const int width = 40, filled = int(fraction * width);
    const double eta = fraction > 0.0 ? elapsed * (1.0 - fraction) / fraction : 0.0;
    std::fprintf(stderr, "\r[%s%s] %5.1f%%  %.1f s left ", std::string(size_t(filled), '#').c_str(),
                 std::string(size_t(width - filled), '.').c_str(), 100.0 * fraction, eta);
    drawn_ = true;
  }
  void finish() {
    if (drawn_) std::fprintf(stderr, "\r%80s\r", "");
  }

 private:
  std::chrono::steady_clock::time_point start_;
  std::mutex mutex_;
  double last_ = -1.0;
  bool drawn_ = false;
};

int run_render(const RenderArgs& a) {
  using clock = std::chrono::steady_clock;
  auto seconds_since = [](clock::time_point t) { return std::chrono::duration<double>(clock::now() - t).count(); };
  const Resolution res = parse_resolution(a.resolution);
  rp::RenderSettings settings = render_settings(a, res);
  std::optional<tbb::global_control> limit;
  if (a.threads > 0) limit.emplace(tbb::global_control::max_allowed_parallelism, size_t(a.threads));
  check_backend(a.backend, a.variant);

  auto t = clock::now();
  rp::Scene scene = with_memory_context("loading " + a.scene, [&] { return rp::load_scene(a.scene); });
  for (const std::string& l : a.lights) {
    static const std::regex re(R"(^(.*),([^,]+)$)");
    std::smatch m;
    float intensity = 0.0f;
    bool ok = std::regex_match(l, m, re);
    if (ok) {
      try {
        size_t used = 0;
        intensity = std::stof(m[2].str(), &used);
        ok = used == size_t(m[2].length()) && std::isfinite(intensity) && intensity > 0.0f;
      } catch (const std::exception&) {
        ok = false;
      }
    }
    if (!ok) throw UsageError(rp::cat("--light: '", l, "' is not x,y,z,intensity with intensity > 0"));
    scene.add_light(rp::PointLight{parse_point("--light", m[1].str()), rp::Vec3f(intensity)});
  }
  const double load_s = seconds_since(t);
  const rp::CameraDesc desc = a.camera.apply(scene.camera().value_or(rp::frame_bounds(scene.bounds())));
  std::optional<rp::Camera> camera_or;
  try {
    camera_or.emplace(desc, res.width, res.height);
  } catch (const rp::Error& e) {
    if (a.camera.any()) throw UsageError(e.what());  // a placement the camera flags made impossible
    throw rp::Error(rp::cat(a.scene, ": ", e.what()));
  }
  const rp::Camera& camera = *camera_or;
  const std::unique_ptr<rp::Backend> backend = build_backend(a.backend, a.variant, scene, a.scene);

  ProgressBar bar;
  const rp::RenderResult r = with_memory_context(rp::cat("rendering ", res.width, "x", res.height), [&] {
    return rp::render(scene, *backend, camera, settings, a.quiet ? rp::ProgressFn{} : rp::ProgressFn(std::ref(bar)));
  });
  bar.finish();
  t = clock::now();
  rp::write_image(a.output, r.image);
  if (!a.aov.empty()) rp::write_aovs(a.aov, rp::render_aovs(scene, *backend, camera));
  const double write_s = seconds_since(t);
  if (!a.quiet) {
    const rp::BackendInfo& info = backend->info();
    const rp::RenderStats& s = r.stats;
    const std::string sampling =
        settings.sampler == rp::Sampler::adaptive ? "adaptive" : std::to_string(a.spp) + " spp " + a.sampler;
    std::fprintf(stderr, "raypack: wrote %s (%dx%d, %s) with %s/%s%s%s\n", a.output.c_str(), res.width, res.height,
                 sampling.c_str(), info.name.c_str(), info.variant.c_str(), a.aov.empty() ? "" : " and AOVs to ",
                 a.aov.c_str());
    std::fprintf(stderr, "raypack: %.2f Mrays/s: %llu primary, %llu shadow, %llu reflection, %llu refraction rays\n",
                 double(s.rays()) / s.seconds * 1e-6, (unsigned long long)s.primary, (unsigned long long)s.shadow,
                 (unsigned long long)s.reflection, (unsigned long long)s.refraction);
    std::fprintf(stderr, "raypack: load %.3f s, build %.3f s (%.1f MiB), render %.3f s, write %.3f s\n", load_s,
                 info.build_seconds, double(info.bytes) / (1 << 20), s.seconds, write_s);
    if (settings.sampler == rp::Sampler::adaptive)
      std::fprintf(stderr, "raypack: adaptive sampling traced %llu primary rays where a uniform grid at depth %d needs %llu (%.1f%% saved)\n",
                   (unsigned long long)s.primary, a.adaptive_depth, (unsigned long long)s.uniform_primary,
                   100.0 * (1.0 - double(s.primary) / double(s.uniform_primary)));
  }
  return 0;
}

/// Hit records (with geometric normals) for writing to a hit file.
std::vector<rp::HitRecord> to_records(const rp::Scene& scene, std::span<const rp::Ray> rays, std::span<const rp::Hit> hits) {
  std::vector<rp::HitRecord> out(hits.size());
  for (size_t i = 0; i < hits.size(); ++i)
    if (hits[i].hit())
      out[i] = {hits[i].t, hits[i].prim_id, hits[i].u, hits[i].v, scene.surface(rays[i], hits[i]).geometric_normal};
  return out;
}

rp::Coherence parse_coherence(const std::string& c) {
  if (c == "coherent") return rp::Coherence::coherent;
  if (c == "incoherent") return rp::Coherence::incoherent;
  throw UsageError(rp::cat("--coherence: '", c, "' is not coherent or incoherent"));
}

struct TraceArgs {
  std::string scene = "default", rays, output, backend{rp::kDefaultBackend}, variant = "default";
  std::string coherence = "incoherent";
  int threads = 0;
  bool quiet = false;
};

int run_trace(const TraceArgs& a) {
  check_backend(a.backend, a.variant);
  const rp::Coherence coherence = parse_coherence(a.coherence);
  std::optional<tbb::global_control> limit;
  if (a.threads > 0) limit.emplace(tbb::global_control::max_allowed_parallelism, size_t(a.threads));
  const rp::Scene scene = with_memory_context("loading " + a.scene, [&] { return rp::load_scene(a.scene); });
  const std::vector<rp::Ray> rays = with_memory_context("reading " + a.rays, [&] { return rp::read_rays(a.rays); });
  const auto backend = build_backend(a.backend, a.variant, scene, a.scene);
  std::vector<rp::Hit> hits;
  const auto start = std::chrono::steady_clock::now();
  with_memory_context(rp::cat("tracing ", rays.size(), " rays"), [&] {
    hits.resize(rays.size());
    rp::intersect_parallel(*backend, rays, hits, coherence);
  });
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  with_memory_context("writing " + a.output, [&] { rp::write_hits(a.output, to_records(scene, rays, hits)); });
  if (!a.quiet) {
    const size_t n_hit = size_t(std::count_if(hits.begin(), hits.end(), [](const rp::Hit& h) { return h.hit(); }));
    const size_t invalid = size_t(std::count_if(rays.begin(), rays.end(), [](const rp::Ray& r) { return !rp::valid_ray(r); }));
    std::fprintf(stderr, "raypack: traced %zu rays (%zu hits) with %s/%s in %.3f s (%.2f Mrays/s); wrote %s\n",
                 rays.size(), n_hit, a.backend.c_str(), a.variant.c_str(), seconds,
                 seconds > 0 ? double(rays.size()) / seconds * 1e-6 : 0.0, a.output.c_str());
    if (invalid > 0)
      rp::warn(rp::cat(a.rays, ": ", invalid, " of ", rays.size(), " rays are outside the valid-ray rule (finite, origin "
                       "|x| <= 2^30, largest direction component in [2^-26, 2^31], 0 <= tnear <= tfar) and were "
                       "reported as misses"));
  }
  return 0;
}

struct DiffArgs {
  std::string scene = "default", rays = "primary";
  size_t count = 1 << 20;
  uint64_t seed = 1;
  std::string a{rp::kDefaultBackend}, b = "simd", variant_a = "default", variant_b = "default";
  std::string coherence;
  double tie_tolerance = 1e-6, t_tolerance = 1e-4;
  bool reference = true;
  std::string json, image;
  double min_agreement = 0;
  int threads = 0;
};

/// A side of the diff: a backend by name, or the reference itself.
struct DiffSide {
  std::string label;
  std::vector<rp::Hit> hits;
};

int run_diff(const DiffArgs& a) {
  for (const auto& [name, variant] : {std::pair{a.a, a.variant_a}, std::pair{a.b, a.variant_b}})
    if (name != "reference") check_backend(name, variant);
  std::optional<tbb::global_control> limit;
  if (a.threads > 0) limit.emplace(tbb::global_control::max_allowed_parallelism, size_t(a.threads));
  if (a.count == 0 || a.count > (size_t(1) << 28))
    throw UsageError(rp::cat("--count: ", a.count, " is out of range (1..", size_t(1) << 28, ")"));
  const rp::Scene scene = with_memory_context("loading " + a.scene, [&] { return rp::load_scene(a.scene); });
  const auto t0 = std::chrono::steady_clock::now();

  // The rays: a file, or generated. Camera rays keep their pixels for the mismatch image.
  rp::RaySet set;
  rp::Coherence coherence = rp::Coherence::incoherent;
  if (a.rays == "primary" || a.rays == "diffuse") {
    const int side = std::max(2, int(std::ceil(std::sqrt(double(a.count)))));
    const int w = (side + 3) / 4 * 4, h = (side + 1) / 2 * 2;
    set = rp::primary_rays(scene, w, h);
    coherence = rp::Coherence::coherent;
    if (a.rays == "diffuse") {
      // Bounces from the primary hits (found by the reference), as many rounds of one bounce
      // per hit as it takes to reach --count rays.
      const rp::Reference reference(scene);
      std::vector<rp::ReferenceHit> rh(set.rays.size());
      reference.intersect(set.rays, rh);
      std::vector<rp::Hit> hits(set.rays.size());
      size_t n_hit = 0;
      for (size_t i = 0; i < rh.size(); ++i)
        if (rh[i].hit()) {
          hits[i] = {float(rh[i].t), rh[i].prim_id, float(rh[i].u), float(rh[i].v)};
          ++n_hit;
        }
      if (n_hit == 0) throw rp::Error(rp::cat(a.scene, ": no camera ray hits the scene, so there are no diffuse rays"));
      rp::RaySet bounces;
      for (uint64_t round = 0; bounces.rays.size() < a.count; ++round) {
        const rp::RaySet more = rp::diffuse_rays(scene, set, hits, a.seed + round);
        bounces.rays.insert(bounces.rays.end(), more.rays.begin(), more.rays.end());
        bounces.pixel.insert(bounces.pixel.end(), more.pixel.begin(), more.pixel.end());
      }
      bounces.rays.resize(a.count);
      bounces.pixel.resize(a.count);
      bounces.width = set.width;
      bounces.height = set.height;
      set = std::move(bounces);
      coherence = rp::Coherence::incoherent;
    }
  } else if (a.rays == "random") {
    set = rp::random_rays(scene, a.count, a.seed);
  } else {
    set.rays = with_memory_context("reading " + a.rays, [&] { return rp::read_rays(a.rays); });
  }
  if (!a.coherence.empty()) coherence = parse_coherence(a.coherence);

  std::vector<rp::ReferenceHit> ref;
  if (a.reference || a.a == "reference" || a.b == "reference") {
    const rp::Reference reference(scene);
    ref.resize(set.rays.size());
    reference.intersect(set.rays, ref);
  }
  auto side = [&](const std::string& name, const std::string& variant) {
    DiffSide s{name == "reference" ? name : name + "/" + variant, std::vector<rp::Hit>(set.rays.size())};
    if (name == "reference") {
      for (size_t i = 0; i < ref.size(); ++i)
        if (ref[i].hit()) s.hits[i] = {float(ref[i].t), ref[i].prim_id, float(ref[i].u), float(ref[i].v)};
    } else {
      const auto backend = build_backend(name, variant, scene, a.scene);
      with_memory_context(rp::cat("tracing ", set.rays.size(), " rays"),
                          [&] { rp::intersect_parallel(*backend, set.rays, s.hits, coherence); });
    }
    return s;
  };
  const DiffSide sa = side(a.a, a.variant_a), sb = side(a.b, a.variant_b);
  const rp::DiffOptions options{a.tie_tolerance, a.t_tolerance};
  const rp::DiffResult d = rp::diff_hits(scene, set.rays, sa.hits, sb.hits, a.reference ? std::span<const rp::ReferenceHit>(ref) : std::span<const rp::ReferenceHit>(), options);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  std::printf("raypack diff: scene %s, rays %s%s, %s\n%s", a.scene.c_str(), a.rays.c_str(),
              a.reference ? ", reference: double-precision watertight" : "",
              coherence == rp::Coherence::coherent ? "coherent (packets)" : "incoherent (single rays)",
              rp::format_table(d, sa.label, sb.label).c_str());
  std::printf("(%.2f s)\n", seconds);
  if (!a.json.empty()) {
    const std::string text = rp::to_json(d, a.scene, a.rays, sa.label, sb.label, options);
    rp::write_file(a.json, text);
  }
  if (!a.image.empty()) rp::write_image(a.image, rp::mismatch_image(d, set, sa.hits));
  if (100.0 * d.agreement() < a.min_agreement) {
    std::fprintf(stderr, "raypack: agreement %.5f%% is below --min-agreement %g%%\n", 100.0 * d.agreement(), a.min_agreement);
    return 3;
  }
  return 0;
}

struct InfoArgs {
  std::string scene = "default";
  bool no_backends = false;
};

/// Counts, bounds, degenerate triangles and the bytes of the scene and of each backend.
int run_info(const InfoArgs& a) {
  const auto t0 = std::chrono::steady_clock::now();
  const rp::Scene scene = with_memory_context("loading " + a.scene, [&] { return rp::load_scene(a.scene); });
  const double load_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  size_t vertices = 0, with_normals = 0, with_uvs = 0;
  for (const rp::TriangleMesh& m : scene.meshes()) {
    vertices += m.positions.size();
    with_normals += !m.normals.empty();
    with_uvs += !m.uvs.empty();
  }
  const rp::Box3f b = scene.bounds();
  std::printf("scene        %s (loaded in %.3f s)\n", a.scene.c_str(), load_s);
  std::printf("triangles    %u in %zu mesh(es), %zu vertices (%zu meshes with normals, %zu with uvs)\n",
              scene.triangle_count(), scene.meshes().size(), vertices, with_normals, with_uvs);
  std::printf("analytic     %zu spheres, %zu quadrics, %zu polygons, %zu planes\n", scene.spheres().size(),
              scene.quadrics().size(), scene.polygons().size(), scene.planes().size());
  std::printf("primitives   %u\n", scene.prim_count());
  std::printf("degenerate   %zu zero-area triangles\n", scene.degenerate_triangle_count());
  if (b.empty()) std::printf("bounds       empty\n");
  else
    std::printf("bounds       (%g, %g, %g) - (%g, %g, %g)\n", b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z);
  std::printf("materials    %zu; lights: %zu point, %zu directional; camera: %s\n", scene.materials().size(),
              scene.point_lights().size(), scene.directional_lights().size(),
              scene.camera() ? "from the scene" : "derived from the bounds");
  const double prims = std::max(1.0, double(scene.prim_count()));
  std::printf("scene bytes  %zu (%.1f per primitive)\n", scene.bytes(), double(scene.bytes()) / prims);
  if (a.no_backends) return 0;
  std::printf("\n%-8s %-8s %10s %14s %12s\n", "backend", "variant", "build s", "bytes", "bytes/prim");
  for (const rp::BackendEntry& e : rp::list_backends()) {
    if (!e.available) {
      std::printf("%-8s unavailable: %s\n", e.name.c_str(), e.unavailable_reason.c_str());
      continue;
    }
    const auto backend = build_backend(e.name, "default", scene, a.scene);
    const rp::BackendInfo& i = backend->info();
    std::printf("%-8s %-8s %10.3f %14zu %12.1f", i.name.c_str(), i.variant.c_str(), i.build_seconds, i.bytes,
                double(i.bytes) / prims);
    for (const auto& [key, value] : i.stats) {
      if (value == std::floor(value) && std::abs(value) < 9.0e15)  // counts as integers, never 1.99965e+07
        std::printf("  %s=%lld", key.c_str(), (long long)value);
      else
        std::printf("  %s=%g", key.c_str(), value);
    }
    std::printf("\n");
  }
  return 0;
}

int run_backends() {
  for (const rp::BackendEntry& e : rp::list_backends()) {
    std::string variants;
    for (const std::string& v : e.variants) variants += (variants.empty() ? "" : ", ") + v;
    std::string methods, facts;
    for (const std::string& m : e.coherent_methods) methods += (methods.empty() ? "" : ", ") + m;
    for (const auto& [k, v] : e.facts) facts += (facts.empty() ? "" : ", ") + k + "=" + v;
    std::printf("%-8s %s\n         variants: %s\n         coherent methods: %s\n         %s\n", e.name.c_str(),
                e.available ? e.description.c_str() : ("unavailable: " + e.unavailable_reason).c_str(),
                variants.c_str(), methods.c_str(), facts.c_str());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  rp::install_signal_cleanup();
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
  ra.camera.add_to(render);
  render->add_option("--light", ra.lights, "Add a white point light x,y,z,intensity (repeatable)");
  render->add_option("--aov", ra.aov, "Also write depth, normals, uv and primitive id as a multi-channel .exr");
  render->add_option("--sampler", ra.sampler, "uniform, random, stratified or adaptive")->capture_default_str();
  render->add_option("--adaptive-threshold", ra.adaptive_threshold,
                     "Adaptive: subdivide where corner colours differ by more (any channel)")
      ->check(CLI::Range(0.0f, 1e30f))
      ->capture_default_str();
  render->add_option("--adaptive-depth", ra.adaptive_depth, "Adaptive: most subdivisions per pixel")
      ->check(CLI::Range(0, 8))
      ->capture_default_str();

  TraceArgs ta;
  CLI::App* trace = app.add_subcommand("trace", "Trace a ray file through a backend and write the hits");
  trace->add_option("--scene", ta.scene, "Scene: 'default' or an .obj/.ply file")->capture_default_str();
  trace->add_option("--rays", ta.rays, "Ray file (.csv, or the binary format)")->required();
  trace->add_option("-o,--output", ta.output, "Hit file (.csv, or the binary format)")->required();
  trace->add_option("--backend", ta.backend, "Backend name")->capture_default_str();
  trace->add_option("--variant", ta.variant, "Backend variant")->capture_default_str();
  trace->add_option("--coherence", ta.coherence, "coherent (groups of 8 as packets) or incoherent")->capture_default_str();
  trace->add_option("-t,--threads", ta.threads, "Worker threads (0 = all cores)")->check(CLI::Range(0, 1024));
  trace->add_flag("-q,--quiet", ta.quiet, "Print nothing on success");

  DiffArgs da;
  CLI::App* diff = app.add_subcommand("diff", "The same rays through backends A and B and the double-precision reference");
  diff->add_option("--scene", da.scene, "Scene: 'default' or an .obj/.ply file")->capture_default_str();
  diff->add_option("--rays", da.rays, "primary, diffuse, random, or a ray file")->capture_default_str();
  diff->add_option("--count", da.count, "Generated rays (primary: the nearest packet-aligned square image)")
      ->capture_default_str();
  diff->add_option("--seed", da.seed, "Seed of generated diffuse and random rays")->capture_default_str();
  diff->add_option("-a", da.a, "Backend A, or 'reference'")->capture_default_str();
  diff->add_option("-b", da.b, "Backend B, or 'reference'")->capture_default_str();
  diff->add_option("--variant-a", da.variant_a, "Variant of A")->capture_default_str();
  diff->add_option("--variant-b", da.variant_b, "Variant of B")->capture_default_str();
  diff->add_option("--coherence", da.coherence, "coherent or incoherent (default: coherent for primary rays)");
  diff->add_option("--tie-tolerance", da.tie_tolerance, "Relative t difference of a tie")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  diff->add_option("--t-tolerance", da.t_tolerance, "Relative t difference allowed on the same primitive")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  diff->add_flag("--reference,!--no-reference", da.reference, "Arbitrate with the double-precision reference")
      ->capture_default_str();
  diff->add_option("--json", da.json, "Write the summary as JSON");
  diff->add_option("--image", da.image, "Write the per-ray classes as an image (camera rays)");
  diff->add_option("--min-agreement", da.min_agreement, "Exit with status 3 below this agreement, in percent")
      ->check(CLI::Range(0.0, 100.0));
  diff->add_option("-t,--threads", da.threads, "Worker threads (0 = all cores)")->check(CLI::Range(0, 1024));

  rp::cli::BenchArgs ba;
  int bench_threads = 0;
  CLI::App* bench = app.add_subcommand("bench", "Every backend method on identical rays: speed beside accuracy");
  bench->add_option("--scene", ba.scenes, "Scene: 'default' or a file (repeatable)")->capture_default_str();
  bench->add_option("--size", ba.size, "Primary rays: SIZE x SIZE pixels")->check(CLI::Range(8, 8192))->capture_default_str();
  bench->add_option("--min-runs", ba.min_runs, "Runs over which the spread is judged")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  bench->add_option("--max-runs", ba.max_runs, "Most runs per measurement")->check(CLI::Range(1, 1000))->capture_default_str();
  bench->add_option("--method", ba.method_filter, "Only the methods whose label matches this regular expression");
  bench->add_option("--kind", ba.kinds, "Only these ray kinds: primary, shadow, diffuse (repeatable)");
  bench->add_option("--rays", ba.ray_file, "Time the rays of this ray file (one --scene) instead of the generated kinds");
  bench->add_flag("--any-hit", ba.occlusion, "With --rays: time any-hit (occlusion) queries, not closest hits");
  bench->add_option("--json", ba.json, "Write the results as JSON");
  bench->add_option("--chart", ba.chart, "Also draw the charts (PNG and SVG, with gnuplot)");
  bench->add_option("-t,--threads", bench_threads, "Worker threads (0 = all cores)")->check(CLI::Range(0, 1024));

  std::string chart_json, chart_out = "chart.png";
  CLI::App* chart = app.add_subcommand("chart", "Redraw the charts of a saved `raypack bench --json` file");
  chart->add_option("json", chart_json, "The bench JSON")->required();
  chart->add_option("-o,--output", chart_out, "Chart (PNG; an SVG and a -scaling chart are written beside it)")
      ->capture_default_str();

  InfoArgs ia;
  CLI::App* info = app.add_subcommand("info", "Counts, bounds and bytes of a scene and of each backend's structure");
  info->add_option("scene,--scene", ia.scene, "Scene: 'default' or a scene file")->capture_default_str();
  info->add_flag("--no-backends", ia.no_backends, "Skip building the backends");

  app.add_subcommand("backends", "List the backends, their variants and availability");

  rp::cli::StabilityArgs sa;
  int stability_threads = 0;
  CLI::App* stability =
      app.add_subcommand("stability", "Failure rates per method and ray family where intersection methods fail");
  stability->add_option("--scene", sa.scene, "Scene: 'default' or a file; its meshes give the mesh families")
      ->capture_default_str();
  stability->add_option("--rays", sa.rays, "Rays per family")->check(CLI::Range(1, 1 << 22))->capture_default_str();
  stability->add_option("--seed", sa.seed, "Seed of every family's rays")->capture_default_str();
  stability->add_option("--t-tolerance", sa.t_tolerance, "Relative t difference counted as an error")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  stability->add_option("--method", sa.methods,
                        "Backend method backend/variant (repeatable; default embree/default, embree/robust, "
                        "simd/default, simd/watertight)");
  stability->add_option("--family", sa.families, "Run only this family (repeatable; see --list)");
  stability->add_flag("--list", sa.list, "List the families and scalar methods");
  stability->add_option("--json", sa.json, "Write the results as JSON");
  stability->add_option("--chart", sa.chart, "Draw the chart (PNG and SVG beside it, with gnuplot)");
  stability->add_option("-t,--threads", stability_threads, "Worker threads (0 = all cores)")->check(CLI::Range(0, 1024));

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "raypack: " << rp::one_line(e.what()) << " (see raypack --help)\n";
    return 2;
  }
  try {
    // A chart format the extension does not name is a bad flag, found before any work.
    for (const auto& [flag, file] : {std::pair{"--chart", ba.chart}, std::pair{"--chart", sa.chart},
                                     std::pair{"-o", *chart ? chart_out : std::string()}}) {
      if (file.empty()) continue;
      try {
        rp::cli::chart_format(file);
      } catch (const rp::Error& e) {
        throw UsageError(rp::cat(flag, ": ", e.what()));
      }
    }
    if (*render) return run_render(ra);
    if (*trace) return run_trace(ta);
    if (*diff) return run_diff(da);
    if (*info) return run_info(ia);
    if (*bench) {
      if (ba.max_runs < ba.min_runs) throw UsageError(rp::cat("--max-runs: ", ba.max_runs, " is below --min-runs ", ba.min_runs));
      std::optional<tbb::global_control> limit;
      if (bench_threads > 0) limit.emplace(tbb::global_control::max_allowed_parallelism, size_t(bench_threads));
      return rp::cli::run_bench(ba);
    }
    if (*stability) {
      std::optional<tbb::global_control> limit;
      if (stability_threads > 0) limit.emplace(tbb::global_control::max_allowed_parallelism, size_t(stability_threads));
      return rp::cli::run_stability(sa);
    }
    if (*chart) {
      rp::cli::draw_charts(chart_json, chart_out);
      std::fprintf(stderr, "raypack: wrote %s\n", chart_out.c_str());
      return 0;
    }
    return run_backends();
  } catch (const UsageError& e) {
    std::cerr << "raypack: " << rp::one_line(e.what()) << '\n';
    return 2;
  } catch (const rp::Error& e) {
    std::cerr << "raypack: " << rp::one_line(e.what()) << '\n';
    return 1;
  } catch (const std::bad_alloc&) {
    std::cerr << "raypack: out of memory: an allocation of " << rp::cli::failed_allocation_bytes() << " bytes failed\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "raypack: internal error: " << rp::one_line(e.what()) << '\n';
    return 1;
  }
}
