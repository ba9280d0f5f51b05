#include "cli/args.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <cstdarg>
#include <cmath>

#include "backends/registry.h"
#include "base/text.h"
#include "cli/out_of_memory.h"
#include "core/ray.h"
#include "io/loaders/load.h"
#include "render/camera.h"

namespace rp::cli {

std::string nearest(const std::string& word, const std::vector<std::string>& candidates) {
  std::string best;
  if (word.size() <= 2) return best;  // -x: every short flag is one edit away
  size_t best_distance = std::max<size_t>(1, word.size() / 3) + 1;
  for (const std::string& c : candidates) {
    // Levenshtein distance, one row at a time.
    std::vector<size_t> row(c.size() + 1);
    for (size_t j = 0; j <= c.size(); ++j) row[j] = j;
    for (size_t i = 1; i <= word.size(); ++i) {
      size_t diagonal = row[0];
      row[0] = i;
      for (size_t j = 1; j <= c.size(); ++j) {
        const size_t up = row[j];
        row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (word[i - 1] == c[j - 1] ? 0 : 1)});
        diagonal = up;
      }
    }
    if (row[c.size()] < best_distance) {
      best_distance = row[c.size()];
      best = c;
    }
  }
  return best;
}

std::string parse_error_message(const CLI::App& app, const CLI::ParseError& error, int argc, char** argv) {
  const std::string what = error.what();
  // The subcommand given, when argv names one.
  const CLI::App* sub = nullptr;
  std::vector<std::string> commands;
  for (const CLI::App* c : app.get_subcommands({})) commands.push_back(c->get_name());
  std::string first;
  for (int i = 1; i < argc && first.empty(); ++i)
    if (argv[i][0] != '-') first = argv[i];
  if (!first.empty()) {
    for (const CLI::App* c : app.get_subcommands({}))
      if (c->get_name() == first) sub = c;
    if (!sub) {
      const std::string guess = nearest(first, commands);
      return cat("unknown subcommand '", first, "'", guess.empty() ? "" : cat("; did you mean '", guess, "'?"),
                 " (see raypack --help)");
    }
  }
  const std::string help = sub ? cat("raypack ", sub->get_name(), " --help") : std::string("raypack --help");
  // An unknown flag (CLI11 reports the arguments it did not expect): the nearest of the
  // subcommand's own. Values that start with '-' (-1, -0.5,2,3) are not flags.
  if (sub && dynamic_cast<const CLI::ExtrasError*>(&error)) {
    std::vector<std::string> flags;
    for (const CLI::Option* o : sub->get_options()) {
      for (const std::string& n : o->get_lnames()) flags.push_back("--" + n);
      for (const std::string& n : o->get_snames()) flags.push_back("-" + n);
    }
    for (int i = 1; i < argc; ++i) {
      std::string arg = argv[i];
      const size_t name = arg.find_first_not_of('-');
      if (name == 0 || name > 2 || name == std::string::npos || !std::isalpha(static_cast<unsigned char>(arg[name])))
        continue;
      arg = arg.substr(0, arg.find('='));
      if (std::find(flags.begin(), flags.end(), arg) != flags.end() || arg == "--help" || arg == "-h") continue;
      const std::string guess = nearest(arg, flags);
      return cat(sub->get_name(), ": unknown flag '", arg, "'", guess.empty() ? "" : cat("; did you mean ", guess, "?"),
                 " (see ", help, ")");
    }
  }
  return cat(one_line(what), " (see ", help, ")");
}

CLI::Option* add_scene_option(CLI::App* app, std::string& scene) {
  return app->add_option("--scene", scene, "Scene: 'default' or a scene file (.obj, .ply, .gltf, .glb, .json)")
      ->capture_default_str();
}

void add_up_axis_option(CLI::App* app, std::string& up_axis) {
  app->add_option("--up-axis", up_axis,
                  "x, y or z: the axis pointing up in the scene file, which sets where a scene without a camera is "
                  "seen from (default: what the file says; Y)");
}

std::optional<int> parse_up_axis(const std::string& up_axis) {
  if (up_axis.empty()) return std::nullopt;
  if (up_axis == "x" || up_axis == "X") return 0;
  if (up_axis == "y" || up_axis == "Y") return 1;
  if (up_axis == "z" || up_axis == "Z") return 2;
  throw UsageError(cat("--up-axis: '", up_axis, "' is not x, y or z"));
}

CLI::Option* add_time_option(CLI::App* app, std::string& time) {
  return app->add_option("--time", time,
                         "Seconds into the scene's animation: the pose to load it at (default: its rest pose)");
}

std::optional<double> parse_time(const std::string& time) {
  if (time.empty()) return std::nullopt;
  try {
    size_t used = 0;
    const double t = std::stod(time, &used);
    if (used == time.size() && std::isfinite(t)) return t;
  } catch (const std::exception&) {
  }
  throw UsageError(cat("--time: '", time, "' is not a number of seconds (a finite number)"));
}

void add_backend_options(CLI::App* app, std::string& backend, std::string& variant) {
  app->add_option("--backend", backend, "Backend name (see `raypack backends`)")->capture_default_str();
  app->add_option("--variant", variant, "Backend variant (see `raypack backends`)")->capture_default_str();
}

void add_threads_option(CLI::App* app, int& threads) {
  app->add_option("-t,--threads", threads, "Worker threads (0 = all cores)")->check(CLI::Range(0, 1024));
}

void add_quiet_flag(CLI::App* app, bool& quiet) {
  app->add_flag("-q,--quiet", quiet, "Print nothing on success");
}

void say(std::FILE* out, const char* format, ...) {
  if (!out) return;
  va_list args;
  va_start(args, format);
  std::vfprintf(out, format, args);
  va_end(args);
}

void check_method(const std::string& backend_flag, const std::string& backend, const std::string& variant_flag,
                  const std::string& variant) {
  if (const std::optional<MethodProblem> p = rp::check_method(backend, variant))
    throw UsageError(cat(p->variant ? variant_flag : backend_flag, ": ", p->message));
}

void check_file_name(const std::string& flag, const std::string& path, void (*check)(const std::string&)) {
  try {
    check(path);
  } catch (const Error& e) {
    throw UsageError(cat(flag, ": ", e.what()));
  }
}

void check_distinct_files(const std::vector<NamedFile>& inputs, const std::vector<NamedFile>& outputs) {
  try {
    check_distinct(inputs, outputs);
  } catch (const Error& e) {
    throw UsageError(e.what());
  }
}

Scene load_scene_or_default(const std::string& path, const std::string& up_axis) {
  return std::move(load_animated_scene_or_default(path, up_axis).scene);
}

AnimatedScene load_animated_scene_or_default(const std::string& path, const std::string& up_axis) {
  const std::optional<int> up = parse_up_axis(up_axis);
  return with_memory_context("loading " + path, [&] { return load_animated_scene(path, up); });
}

void frame_rest_pose(AnimatedScene& s) {
  if (!s.animation.empty() && !s.scene.camera()) s.scene.set_camera(frame_bounds(s.scene.bounds(), s.scene.up_axis()));
}

void pose(AnimatedScene& s, std::optional<double> time) {
  if (time) with_memory_context(cat("posing the scene at ", *time, " s"), [&] { s.animation.apply(s.scene, *time); });
}

std::unique_ptr<Backend> build_backend(const std::string& name, const std::string& variant, const Scene& scene,
                                       const std::string& scene_name) {
  const std::string what =
      cat("building the ", name, "/", variant, " structure of ", scene_name, " (", scene.prim_count(), " primitives)");
  try {
    return with_memory_context(
        what, [&] { return make_backend(name, scene, {.variant = variant, .device_config = {}, .coherent_method = {}, .incoherent_method = {}}); });
  } catch (const Error& e) {
    if (std::string_view(e.what()).starts_with("out of memory")) throw;
    throw Error(cat(what, ": ", e.what()));
  }
}

bool parse_floats(const std::string& text, std::span<float> out) {
  size_t at = 0;
  for (size_t k = 0; k < out.size(); ++k) {
    const size_t end = k + 1 < out.size() ? text.find(',', at) : text.size();
    if (end == std::string::npos) return false;
    const std::string field = text.substr(at, end - at);
    const size_t first = field.find_first_not_of(" \t"), last = field.find_last_not_of(" \t");
    if (first == std::string::npos) return false;
    const std::string number = field.substr(first, last - first + 1);
    try {
      size_t used = 0;
      out[k] = std::stof(number, &used);
      if (used != number.size() || !std::isfinite(out[k])) return false;
    } catch (const std::exception&) {
      return false;
    }
    at = end + 1;
  }
  return true;
}

Vec3f parse_vec3(const std::string& flag, const std::string& text) {
  float v[3];
  if (!parse_floats(text, v)) throw UsageError(cat(flag, ": '", text, "' is not three finite numbers x,y,z"));
  return {v[0], v[1], v[2]};
}

Vec3f parse_point(const std::string& flag, const std::string& text) {
  const Vec3f p = parse_vec3(flag, text);
  if (!in_coordinate_range(p))
    throw UsageError(cat(flag, ": '", text, "' is outside the supported coordinate range |x| <= 1073741824 (2^30)"));
  return p;
}

Coherence parse_coherence(const std::string& flag, const std::string& text) {
  if (text == "coherent") return Coherence::coherent;
  if (text == "incoherent") return Coherence::incoherent;
  throw UsageError(cat(flag, ": '", text, "' is not coherent or incoherent"));
}

}  // namespace rp::cli
