#pragma once
/// The renderer: pinhole primary rays in 4x2-pixel packets, Blinn-Phong shading with shadow
/// rays and mirror reflection, tiles in parallel (TBB), deterministic for any thread count.

#include <cstdint>
#include <vector>

#include "engine/backend.h"
#include "engine/camera.h"
#include "engine/scene.h"

namespace rp {

/// Linear RGB float image, row-major from the top row, 3 floats per pixel.
struct Image {
  int width = 0, height = 0;
  std::vector<float> rgb;
};

struct RenderSettings {
  int width = 1024, height = 768;
  int spp = 1;             ///< samples per pixel, >= 1; stratified jitter over the largest square grid
  uint64_t seed = 0;       ///< seeds the per-pixel sample streams
  int max_depth = 3;       ///< mirror bounces after the primary hit
};

/// Rays traced, by kind, and wall time.
struct RenderStats {
  uint64_t primary = 0, shadow = 0, reflection = 0;
  double seconds = 0;
  uint64_t rays() const { return primary + shadow + reflection; }
};

struct RenderResult {
  Image image;
  RenderStats stats;
};

/// Renders `scene` as seen by `camera` (camera.width()/height() must equal settings'),
/// tracing with `backend`. The result depends only on the inputs, never on thread count.
RenderResult render(const Scene& scene, const Backend& backend, const Camera& camera,
                    const RenderSettings& settings);

/// Sample position in [0, 1)^2 for sample s of a pixel: stratified jitter on the largest
/// m x m grid with m*m <= spp (samples s >= m*m are uniform random), from a counter-based
/// hash of (seed, pixel, sample) so every pixel's stream is independent of scheduling.
Vec2f pixel_sample(uint64_t seed, uint64_t pixel, int sample, int spp);

/// Lens position in [0, 1)^2 for sample s of a pixel (thin-lens cameras), from a stream
/// independent of pixel_sample's.
Vec2f lens_sample(uint64_t seed, uint64_t pixel, int sample);

}  // namespace rp
