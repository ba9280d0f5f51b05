#pragma once
// What every raypack subcommand shares: the usage-error type (exit status 2), the flags that
// mean the same in every subcommand (-t/--threads, -q/--quiet, --backend/--variant), and the
// parsers of values that several subcommands take (points, coherence).

#include <cstdio>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "base/error.h"
#include "base/math.h"
#include "core/backend.h"
#include "core/scene.h"
#include "core/thread_limit.h"
#include "io/loaders/animation.h"
#include "io/output_file.h"

namespace CLI {
class App;
class Option;
class ParseError;
}

namespace rp::cli {

/// A mistake in the flags or their values: reported like CLI11's own parse errors, exit status
/// 2, before any work starts.
struct UsageError : Error {
  using Error::Error;
};

/// Of `candidates`, the one nearest to `word` (a mistyped flag or subcommand) by edit
/// distance, when it is within 2 edits or a third of the word; empty when none is.
std::string nearest(const std::string& word, const std::vector<std::string>& candidates);

/// The one-line message for a command line CLI11 refused (`error`): an unknown subcommand or
/// flag gets the nearest valid one as a suggestion, and every message points at the help of
/// the subcommand given (`raypack render --help`) or of raypack.
std::string parse_error_message(const CLI::App& app, const CLI::ParseError& error, int argc, char** argv);

/// --scene: 'default' or a scene file, bound to `scene`. Returns the option (a command may
/// require it).
CLI::Option* add_scene_option(CLI::App* app, std::string& scene);

/// --up-axis: x, y or z, the axis that points up in a scene file, where a scene without a
/// camera is framed from and lit (Scene::set_up_axis); empty: what the file says (Y unless a
/// format defines its own).
void add_up_axis_option(CLI::App* app, std::string& up_axis);

/// --time: seconds into the scene's animation, the pose the command loads the scene at (every
/// animation of the file plays at once from 0 s; each holds its first and last values before
/// and after its keyframes); empty: the rest pose. Returns the option, for flags it excludes.
CLI::Option* add_time_option(CLI::App* app, std::string& time);

/// --time's value in seconds: any finite number (nothing for ""), or a usage error naming the
/// flag.
std::optional<double> parse_time(const std::string& time);

/// --backend and --variant: a backend by name and its variant (see `raypack backends`).
void add_backend_options(CLI::App* app, std::string& backend, std::string& variant);

/// -t,--threads: worker threads (0 = all cores), bound to `threads`; a command holds
/// rp::ThreadLimit(threads) while it works (core/thread_limit.h).
void add_threads_option(CLI::App* app, int& threads);

/// -q,--quiet: print nothing on success (results still go to the files asked for).
void add_quiet_flag(CLI::App* app, bool& quiet);

/// printf to `out`, or nothing when `out` is null (a command run with -q).
__attribute__((format(printf, 2, 3))) void say(std::FILE* out, const char* format, ...);

/// Throws UsageError naming `backend_flag` or `variant_flag` (the flags as the user gave them,
/// e.g. -b and --variant-b) when the registry cannot build backend/variant here.
void check_method(const std::string& backend_flag, const std::string& backend, const std::string& variant_flag,
                  const std::string& variant);

/// Throws UsageError naming `flag` when check(path) (e.g. rp::check_ray_file_name) refuses
/// the file name, so a bad name is found before any work.
void check_file_name(const std::string& flag, const std::string& path, void (*check)(const std::string&));

/// Throws UsageError when an output is the same file as an input or another output
/// (rp::check_distinct, io/output_file.h), before any work.
void check_distinct_files(const std::vector<NamedFile>& inputs, const std::vector<NamedFile>& outputs);

/// The scene at `path` ('default' or a file), with an out-of-memory failure named as such;
/// `up_axis` as --up-axis takes it (a usage error naming the flag when it is not x, y or z).
Scene load_scene_or_default(const std::string& path, const std::string& up_axis = "");

/// The same scene at its rest pose with its animation (rp::load_animated_scene).
AnimatedScene load_animated_scene_or_default(const std::string& path, const std::string& up_axis = "");

/// Gives an animated scene that has no camera the one framing its rest pose (frame_bounds, as
/// a still scene is framed), so that it is seen from one place at every time: the frames of an
/// animation, and a render at --time t, share one view. A still scene, or one with a camera
/// (which the animation may move), is left as it is.
void frame_rest_pose(AnimatedScene& scene);

/// `scene` posed at `time` (SceneAnimation::apply), with an out-of-memory failure named as
/// such; nothing: left at its rest pose.
void pose(AnimatedScene& scene, std::optional<double> time);

/// --up-axis's value as an axis index (nothing for ""), or a usage error naming the flag.
std::optional<int> parse_up_axis(const std::string& up_axis);

/// The backend `name`/`variant` built over `scene` (loaded from `scene_name`), with an
/// out-of-memory failure named as such.
std::unique_ptr<Backend> build_backend(const std::string& name, const std::string& variant, const Scene& scene,
                                       const std::string& scene_name);

/// Exactly out.size() comma-separated finite numbers (blanks around each allowed) into `out`;
/// false when `text` is anything else.
bool parse_floats(const std::string& text, std::span<float> out);

/// "x,y,z" as a vector, or a usage error naming the flag.
Vec3f parse_vec3(const std::string& flag, const std::string& text);

/// "x,y,z" as a point, which must lie in the coordinate range every backend traces (core/ray.h).
Vec3f parse_point(const std::string& flag, const std::string& text);

/// "coherent" or "incoherent", or a usage error naming the flag.
Coherence parse_coherence(const std::string& flag, const std::string& text);

}  // namespace rp::cli
