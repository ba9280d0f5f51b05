#include "cli/render_cmd.h"

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <optional>
#include <regex>

#include "cli/args.h"
#include "cli/frames.h"
#include "cli/out_of_memory.h"
#include "mpi/render_ranks.h"
#include "mpi/same_inputs.h"
#include "render/camera.h"
#include "render/image_io.h"
#include "render/render.h"

namespace rp::cli {

namespace {

struct Resolution {
  int width, height;
};

Resolution parse_resolution(const std::string& text) {
  static const std::regex re(R"(^\s*(\d{1,9})\s*[xX]\s*(\d{1,9})\s*$)");
  std::smatch m;
  if (!std::regex_match(text, m, re))
    throw UsageError(cat("--resolution: '", text, "' is not WIDTHxHEIGHT (e.g. 1920x1080)"));
  const long long w = std::stoll(m[1]), h = std::stoll(m[2]);
  try {
    check_image_size("--resolution", w, h);
  } catch (const Error& e) {
    throw UsageError(e.what());
  }
  return {int(w), int(h)};
}

/// "x,y,z,intensity" as a white point light, or a usage error naming --light.
PointLight parse_light(const std::string& text) {
  float v[4];
  if (!parse_floats(text, v) || !(v[3] > 0.0f))
    throw UsageError(cat("--light: '", text, "' is not four numbers x,y,z,intensity with intensity > 0"));
  const Vec3f p{v[0], v[1], v[2]};
  if (!in_coordinate_range(p))
    throw UsageError(cat("--light: '", text, "' is outside the supported coordinate range |x| <= 1073741824 (2^30)"));
  return PointLight{p, Vec3f(v[3])};
}

CameraDesc apply(const CameraArgs& a, CameraDesc c) {
  if (!a.model.empty()) {
    if (a.model == "pinhole") c.model = CameraModel::pinhole;
    else if (a.model == "panoramic") c.model = CameraModel::panoramic;
    else if (a.model == "fisheye") c.model = CameraModel::fisheye;
    else if (a.model == "thin-lens") c.model = CameraModel::thin_lens;
    else throw UsageError(cat("--camera: '", a.model, "' is not pinhole, panoramic, fisheye or thin-lens"));
  }
  if (!a.eye.empty()) c.eye = parse_point("--eye", a.eye);
  if (!a.look_at.empty()) c.look_at = parse_point("--look-at", a.look_at);
  if (!a.up.empty()) c.up = parse_vec3("--up", a.up);
  if (a.fov > 0) c.vfov_degrees = a.fov;
  if (a.fisheye_fov > 0) c.fisheye_fov_degrees = a.fisheye_fov;
  if (a.aperture >= 0) c.aperture = a.aperture;
  if (a.focus_distance >= 0) c.focus_distance = a.focus_distance;
  if (a.aperture >= 0 && c.model == CameraModel::thin_lens && !in_coordinate_range(abs(c.eye) + Vec3f(a.aperture)))
    throw UsageError(cat("--aperture: ", a.aperture, " puts the lens around the eye (", c.eye.x, ", ", c.eye.y, ", ",
                         c.eye.z, ") outside the supported coordinate range |x| <= 1073741824 (2^30)"));
  return c;
}

RenderSettings render_settings(const RenderArgs& a, const Resolution& res) {
  RenderSettings settings;
  settings.width = res.width;
  settings.height = res.height;
  settings.spp = a.spp;
  settings.seed = a.seed;
  settings.max_depth = a.max_depth;
  settings.adaptive_threshold = a.adaptive_threshold;
  settings.adaptive_depth = a.adaptive_depth;
  if (a.sampler == "uniform") settings.sampler = Sampler::uniform;
  else if (a.sampler == "random") settings.sampler = Sampler::random;
  else if (a.sampler == "stratified") settings.sampler = Sampler::stratified;
  else if (a.sampler == "adaptive") settings.sampler = Sampler::adaptive;
  else throw UsageError(cat("--sampler: '", a.sampler, "' is not uniform, random, stratified or adaptive"));
  const int m = int(std::sqrt(double(a.spp)));
  if (settings.sampler == Sampler::uniform && m * m != a.spp)
    throw UsageError(cat("--spp: ", a.spp, " is not a square, which the uniform sampler needs (1, 4, 9, ...)"));
  return settings;
}

/// The statistics of several frames as those of one render: rays and seconds summed.
void add_frame(RenderStats& all, const RenderStats& frame) {
  all.primary += frame.primary;
  all.shadow += frame.shadow;
  all.reflection += frame.reflection;
  all.refraction += frame.refraction;
  all.uniform_primary += frame.uniform_primary;
  all.seconds += frame.seconds;
}

/// The same for what one rank did.
void add_frame(dist::RankRender& all, const dist::RankRender& frame) {
  all.tiles += frame.tiles;
  all.threads = frame.threads;
  all.seconds += frame.seconds;
  all.handout.requests += frame.handout.requests;
  all.handout.wait_seconds += frame.handout.wait_seconds;
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

}  // namespace

void CameraArgs::add_to(CLI::App* app) {
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

bool CameraArgs::any() const {
  return !model.empty() || !eye.empty() || !look_at.empty() || !up.empty() || fov > 0 || fisheye_fov > 0 ||
         aperture >= 0 || focus_distance >= 0;
}

CLI::App* RenderArgs::add_to(CLI::App& app) {
  CLI::App* c = app.add_subcommand("render", "Render a scene (the embedded default or a file) to an image");
  add_scene_option(c, scene);
  add_up_axis_option(c, up_axis);
  CLI::Option* at = add_time_option(c, time);
  CLI::Option* range =
      c->add_option("--frames", frames,
                    "Render frames FIRST:LAST of the animation, frame n at n / fps seconds; the run of '#' in -o "
                    "(and --aov) is the frame number")
          ->excludes(at);
  c->add_option("--fps", fps, "Frames per second of --frames")
      ->check(CLI::Range(0.001, 1000000.0))
      ->needs(range)
      ->capture_default_str();
  c->add_option("-o,--output", output, "Output image; format by extension (.png, .exr, ...)")->capture_default_str();
  c->add_option("--resolution", resolution, "Image size WIDTHxHEIGHT")->capture_default_str();
  add_backend_options(c, backend, variant);
  c->add_option("--spp", spp, "Samples per pixel")->check(CLI::Range(1, kMaxSpp))->capture_default_str();
  add_threads_option(c, threads);
  c->add_option("--seed", seed, "Seed of the per-pixel sample streams")->capture_default_str();
  c->add_option("--max-depth", max_depth, "Mirror bounces after the primary hit")
      ->check(CLI::Range(0, 64))
      ->capture_default_str();
  add_quiet_flag(c, quiet);
  camera.add_to(c);
  c->add_option("--light", lights, "Add a white point light x,y,z,intensity (repeatable)");
  c->add_option("--aov", aov, "Also write depth, normals, uv and primitive id as a multi-channel .exr");
  c->add_option("--sampler", sampler, "uniform, random, stratified or adaptive")->capture_default_str();
  c->add_option("--adaptive-threshold", adaptive_threshold,
                "Adaptive: subdivide where corner colours differ by more (any channel)")
      ->check(CLI::Range(0.0f, 1e30f))
      ->capture_default_str();
  c->add_option("--adaptive-depth", adaptive_depth, "Adaptive: most subdivisions per pixel")
      ->check(CLI::Range(0, 8))
      ->capture_default_str();
  c->add_flag("--measure-traces", measure_traces,
              "Also trace the render's own rays again without the rest of the render, and print both rates");
  c->add_option("--tiles-per-request", tiles_per_request,
                "Under mpirun: tiles rank 0 hands another rank per request (0: a share of what is left)")
      ->check(CLI::Range(0, 1 << 20))
      ->capture_default_str();
  return c;
}

int run_render(const RenderArgs& a, const dist::Comm& comm) {
  using clock = std::chrono::steady_clock;
  auto seconds_since = [](clock::time_point t) { return std::chrono::duration<double>(clock::now() - t).count(); };
  const bool across = comm.size() > 1, quiet = a.quiet || !comm.root();
  // The flags, checked on every rank before any work.
  struct Flags {
    Resolution res;
    RenderSettings settings;
    std::vector<PointLight> lights;
    std::optional<double> time;        ///< --time
    std::optional<FrameRange> frames;  ///< --frames
  };
  const Flags f = dist::together(comm, [&] {
    if (across && a.measure_traces)
      throw UsageError("--measure-traces: times the traces of one process; start it without mpirun");
    const Resolution res = parse_resolution(a.resolution);
    Flags flags{res, render_settings(a, res), {}, parse_time(a.time), std::nullopt};
    for (const std::string& l : a.lights) flags.lights.push_back(parse_light(l));
    check_method("--backend", a.backend, "--variant", a.variant);
    if (!a.frames.empty()) {
      flags.frames = parse_frames(a.frames);
      if (a.measure_traces) throw UsageError("--measure-traces: times the traces of one image; not with --frames");
      check_frame_pattern("-o", a.output, *flags.frames);
      if (!a.aov.empty()) check_frame_pattern("--aov", a.aov, *flags.frames);
    }
    if (comm.root()) {  // rank 0 writes the outputs (the first frame's names stand for every frame's)
      const int64_t first = flags.frames ? flags.frames->first : 0;
      const std::string output = frame_path(a.output, first), aov = a.aov.empty() ? "" : frame_path(a.aov, first);
      check_distinct_files({{"--scene", a.scene}}, {{"-o", output}, {"--aov", aov}});
      check_file_name("-o", output, check_image_output);
      if (!aov.empty()) check_file_name("--aov", aov, check_aov_output);
    }
    return flags;
  });
  const Resolution& res = f.res;
  const ThreadLimit limit(a.threads);
  // What is rendered: one image (at --time, or the rest pose), or each frame at frame / fps.
  struct Shot {
    std::optional<double> time;
    std::string output, aov;
  };
  const int64_t shots = f.frames ? f.frames->count() : 1;
  const auto shot = [&](int64_t k) {
    if (!f.frames) return Shot{f.time, a.output, a.aov};
    const int64_t frame = f.frames->first + k;
    return Shot{double(frame) / a.fps, frame_path(a.output, frame), a.aov.empty() ? "" : frame_path(a.aov, frame)};
  };

  // Every rank loads the scene, poses it and builds its own backend (replicated data).
  auto t = clock::now();
  AnimatedScene animated = dist::together(comm, [&] {
    AnimatedScene s = load_animated_scene_or_default(a.scene, a.up_axis);
    for (const PointLight& l : f.lights) s.scene.add_light(l);
    frame_rest_pose(s);
    return s;
  });
  const Scene& scene = animated.scene;
  const double load_s = seconds_since(t);
  if (across) dist::check_same_inputs(comm, {{"--scene", a.scene, dist::scene_digest(scene, animated.animation)}});
  dist::together(comm, [&] { pose(animated, shot(0).time); });
  const std::unique_ptr<Backend> backend =
      dist::together(comm, [&] { return build_backend(a.backend, a.variant, scene, a.scene); });

  ProgressBar bar;
  RenderStats stats;
  std::vector<dist::RankRender> ranks;
  double update_s = 0, write_s = 0;
  TraceLog log;
  double trace_s = 0;
  for (int64_t k = 0; k < shots; ++k) {
    const Shot now = shot(k);
    if (k > 0) {  // the next frame's pose, and the backend brought up to date
      t = clock::now();
      dist::together(comm, [&] {
        pose(animated, now.time);
        with_memory_context(cat("updating the ", a.backend, "/", a.variant, " structure"), [&] { backend->update(); });
      });
      update_s += seconds_since(t);
    }
    std::optional<Camera> camera_or;
    dist::together(comm, [&] {
      const CameraDesc desc = apply(a.camera, scene.camera().value_or(frame_bounds(scene.bounds(), scene.up_axis())));
      try {
        camera_or.emplace(desc, res.width, res.height);
      } catch (const Error& e) {
        if (a.camera.any()) throw UsageError(e.what());  // a placement the camera flags made impossible
        throw Error(cat(a.scene, now.time ? cat(" at ", *now.time, " s") : "", ": ", e.what()));
      }
    });
    const Camera& camera = *camera_or;
    // The bar covers every frame: frame k's fraction f is (k + f) / shots of the whole.
    const ProgressFn progress =
        quiet ? ProgressFn{} : ProgressFn([&](double fraction) { bar((double(k) + fraction) / double(shots)); });
    RenderResult r;
    if (across) {
      std::optional<TileRenderer> tiles;
      dist::together(comm, [&] { tiles.emplace(scene, *backend, camera, f.settings); });
      t = clock::now();
      dist::RenderAcross all = dist::render_across(comm, *tiles, a.tiles_per_request, progress);
      r.image = std::move(all.image);
      r.stats = tiles->stats(all.counts, seconds_since(t));
      if (ranks.empty()) ranks.resize(all.ranks.size());
      for (size_t i = 0; i < all.ranks.size(); ++i) add_frame(ranks[i], all.ranks[i]);
    } else {
      r = with_memory_context(cat("rendering ", res.width, "x", res.height),
                              [&] { return render(scene, *backend, camera, f.settings, progress); });
    }
    add_frame(stats, r.stats);
    // The render again, untimed, recording its calls to the backend (the same rays: a render
    // depends on its inputs only), then those calls alone, twice: the second is timed.
    if (a.measure_traces) {
      with_memory_context(cat("recording the rays of ", res.width, "x", res.height),
                          [&] { return render(scene, *backend, camera, f.settings, {}, &log); });
      replay_traces(log, *backend);
      trace_s = replay_traces(log, *backend);
    }
    // Rank 0 writes the image (and the AOVs, which it traces alone: primary rays only).
    t = clock::now();
    dist::together(comm, [&] {
      if (!comm.root()) return;
      write_image(now.output, r.image);
      if (!now.aov.empty()) write_aovs(now.aov, render_aovs(scene, *backend, camera));
    });
    write_s += seconds_since(t);
    if (f.frames && !quiet) {
      bar.finish();
      std::fprintf(stderr, "raypack: frame %lld at %g s: wrote %s%s%s\n", (long long)(f.frames->first + k), *now.time,
                   now.output.c_str(), now.aov.empty() ? "" : " and AOVs to ", now.aov.c_str());
    }
  }
  bar.finish();
  struct RankSetup {
    double load, build;
  };
  const std::vector<RankSetup> setups =
      across ? dist::gather_each(comm, RankSetup{load_s, backend->info().build_seconds}) : std::vector<RankSetup>();
  if (!quiet) {
    const BackendInfo& info = backend->info();
    const RenderStats& s = stats;
    const std::string sampling =
        f.settings.sampler == Sampler::adaptive ? "adaptive" : std::to_string(a.spp) + " spp " + a.sampler;
    const std::string what = f.frames ? cat(shots, " frame", shots == 1 ? ", " : "s, ", shot(0).output,
                                            shots == 1 ? "" : cat(" to ", shot(shots - 1).output))
                                      : a.output;
    std::fprintf(stderr, "raypack: wrote %s (%dx%d, %s) with %s/%s%s%s%s\n", what.c_str(), res.width, res.height,
                 sampling.c_str(), info.name.c_str(), info.variant.c_str(),
                 across ? cat(" on ", comm.size(), " ranks").c_str() : "",
                 a.aov.empty() || f.frames ? "" : " and AOVs to ", f.frames ? "" : a.aov.c_str());
    std::fprintf(stderr, "raypack: %.2f Mrays/s: %llu primary, %llu shadow, %llu reflection, %llu refraction rays\n",
                 double(s.rays()) / s.seconds * 1e-6, (unsigned long long)s.primary, (unsigned long long)s.shadow,
                 (unsigned long long)s.reflection, (unsigned long long)s.refraction);
    char updates[64] = "";  // with --frames: the updates between frames
    if (shots > 1)
      std::snprintf(updates, sizeof updates, ", %lld update%s %.3f s", (long long)(shots - 1), shots == 2 ? "" : "s",
                    update_s);
    std::fprintf(stderr, "raypack: load %.3f s, build %.3f s (%.1f MiB)%s, render %.3f s, write %.3f s\n", load_s,
                 info.build_seconds, double(info.bytes) / (1 << 20), updates, s.seconds, write_s);
    for (size_t k = 0; k < ranks.size(); ++k) {
      const dist::RankRender& rr = ranks[k];
      std::fprintf(stderr, "raypack: rank %zu: %llu tiles in %.3f s (%d thread%s; load %.3f s, build %.3f s", k,
                   (unsigned long long)rr.tiles, rr.seconds, rr.threads, rr.threads == 1 ? "" : "s", setups[k].load,
                   setups[k].build);
      if (k > 0)
        std::fprintf(stderr, "; %llu requests, waited %.3f s", (unsigned long long)rr.handout.requests,
                     rr.handout.wait_seconds);
      std::fprintf(stderr, ")\n");
    }
    if (a.measure_traces)
      std::fprintf(stderr,
                   "raypack: the render's %llu rays traced alone: %.3f s, %.2f Mrays/s; the render ran at %.2f of "
                   "that rate (%.0f%% of its time in the traces)\n",
                   (unsigned long long)log.rays(), trace_s, double(log.rays()) / trace_s * 1e-6, trace_s / s.seconds,
                   100.0 * trace_s / s.seconds);
    if (f.settings.sampler == Sampler::adaptive)
      std::fprintf(stderr,
                   "raypack: adaptive sampling traced %llu primary rays where a uniform grid at depth %d needs %llu "
                   "(%.1f%% saved)\n",
                   (unsigned long long)s.primary, a.adaptive_depth, (unsigned long long)s.uniform_primary,
                   100.0 * (1.0 - double(s.primary) / double(s.uniform_primary)));
  }
  return 0;
}

}  // namespace rp::cli
