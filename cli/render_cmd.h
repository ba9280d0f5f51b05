#pragma once
// `raypack render`: a scene (the embedded default or a file) to an image, or the frames of its
// animation to images, with camera, light, sampler and backend flags, a progress bar and a
// statistics line.

#include <cstdint>
#include <string>
#include <vector>

#include "backends/registry.h"
#include "mpi/comm.h"

namespace CLI {
class App;
}

namespace rp::cli {

/// Camera overrides on the command line; each one replaces the scene's value.
struct CameraArgs {
  std::string model, eye, look_at, up;
  float fov = 0, fisheye_fov = 0, aperture = -1, focus_distance = -1;

  void add_to(CLI::App* app);
  /// True when any flag changes the scene's camera.
  bool any() const;
};

struct RenderArgs {
  CameraArgs camera;
  std::vector<std::string> lights;
  std::string aov;
  std::string sampler = "stratified";
  float adaptive_threshold = 0.05f;
  int adaptive_depth = 3;
  std::string scene = "default";
  std::string up_axis;  ///< --up-axis: "" (the file's), x, y or z
  std::string time;     ///< --time: "" (the rest pose) or seconds into the scene's animation
  std::string frames;   ///< --frames: "" (one image) or FIRST:LAST
  double fps = 24;      ///< --fps: frames per second of --frames
  std::string output = "raypack.png";
  std::string resolution = "1024x768";
  std::string backend{kDefaultBackend};
  std::string variant = "default";
  int spp = 1;
  int threads = 0;
  uint64_t seed = 0;
  int max_depth = 3;
  bool quiet = false;
  bool measure_traces = false;
  int tiles_per_request = 0;  ///< under mpirun: tiles per request to rank 0 (0: guided)

  /// Adds the `render` subcommand to `app` with these flags.
  CLI::App* add_to(CLI::App& app);
};

/// Renders and writes the image (and the AOVs when asked), or with --frames each frame's;
/// returns the exit status. Between frames the scene is posed at the next frame's time and the
/// backend updated (Backend::update), not rebuilt. Across the ranks of `comm` when there are
/// several: every rank poses its scene, updates its backend and renders the tiles rank 0 hands
/// it; rank 0 writes the images and prints.
int run_render(const RenderArgs& args, const dist::Comm& comm);

}  // namespace rp::cli
