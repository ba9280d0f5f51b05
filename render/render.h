#pragma once
/// The renderer: primary rays in 4x2-pixel packets, Blinn-Phong shading with shadow rays,
/// Whitted mirror reflection and refraction with Fresnel, the lecture notes' pixel samplers
/// (uniform grid, random, stratified, adaptive), tiles in parallel (TBB), deterministic for
/// any thread count.

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "core/backend.h"
#include "core/scene.h"
#include "render/camera.h"

namespace rp {

/// Linear RGB float image, row-major from the top row, 3 floats per pixel.
struct Image {
  int width = 0, height = 0;
  std::vector<float> rgb;
};

/// How a pixel's sample positions are chosen (lecture "Ray Tracing Basics", antialiasing).
enum class Sampler : uint8_t {
  uniform,     ///< the centres of an n x n grid (spp must be a square)
  random,      ///< uniform random positions
  stratified,  ///< one random position in each cell of the largest m x m grid (m*m <= spp), the rest random
  adaptive,    ///< rays through the pixel-grid corners, cells subdivided where colours differ
};

/// The most samples per pixel a render takes (the CLI's --spp and Python's spp alike).
inline constexpr int kMaxSpp = 65536;

struct RenderSettings {
  int width = 1024, height = 768;
  int spp = 1;  ///< samples per pixel, 1..kMaxSpp (not used by the adaptive sampler)
  Sampler sampler = Sampler::stratified;
  uint64_t seed = 0;       ///< seeds the per-pixel sample streams
  int max_depth = 3;       ///< reflection and refraction bounces after the primary hit
  float adaptive_threshold = 0.05f;  ///< adaptive: subdivide when corner colours differ by more (max channel)
  int adaptive_depth = 3;            ///< adaptive: most subdivisions of a pixel (cells of 1/2^depth pixel)
};

/// Rays traced, by kind, and wall time. For the adaptive sampler, `uniform_primary` is the
/// number of corner rays a uniform grid at the finest subdivision would have traced.
struct RenderStats {
  uint64_t primary = 0, shadow = 0, reflection = 0, refraction = 0;
  uint64_t uniform_primary = 0;
  double seconds = 0;
  uint64_t rays() const { return primary + shadow + reflection + refraction; }
};

struct RenderResult {
  Image image;
  RenderStats stats;
};

/// Every call a render made to its backend, tile by tile in order, for timing the same traces
/// without the rest of the render (replay_traces): the rays of each call, whether it asked for
/// closest or any hits, and its coherence hint.
struct TraceLog {
  struct Call {
    bool any;  ///< occluded() rather than intersect()
    Coherence coherence;
    std::vector<Ray> rays;
  };
  std::vector<std::vector<Call>> tiles;  ///< by tile (row-major over the tile grid)
  uint64_t rays() const;
};

/// Edge of the renderer's square tiles, in pixels; a tile holds 32 packets of 4x2 pixels.
inline constexpr int kTileSize = 16;
inline constexpr int kTilePixels = kTileSize * kTileSize;

/// Rays traced by some of a render's tiles, by kind (the adaptive sampler's corner rays are
/// primary rays).
struct TileCounts {
  uint64_t primary = 0, shadow = 0, reflection = 0, refraction = 0;
  TileCounts& operator+=(const TileCounts& o);
};

/// One render cut into kTileSize-pixel tiles, numbered row-major over the tile grid, that can
/// be rendered one at a time in any order, on any thread or process: a tile's pixels depend on
/// the inputs and its number only (render() is every tile of one of these). Holds references
/// to the scene, backend and camera, which must outlive it.
class TileRenderer {
 public:
  /// Throws rp::Error for settings out of range, as render() does.
  TileRenderer(const Scene& scene, const Backend& backend, const Camera& camera, const RenderSettings& settings);
  ~TileRenderer();
  TileRenderer(const TileRenderer&) = delete;
  TileRenderer& operator=(const TileRenderer&) = delete;

  /// A thread's working memory for render(): its arrays keep their size from tile to tile.
  /// One per thread (two calls at once must not share one); it holds nothing a tile's pixels
  /// depend on.
  class Scratch {
   public:
    Scratch();
    ~Scratch();
    Scratch(const Scratch&) = delete;
    Scratch& operator=(const Scratch&) = delete;

   private:
    friend class TileRenderer;
    struct Work;
    std::unique_ptr<Work> work_;
  };

  const RenderSettings& settings() const;
  int tiles_x() const;
  int tiles_y() const;
  int tile_count() const { return tiles_x() * tiles_y(); }

  /// Renders tile `index` (in [0, tile_count())) into `pixels`, row-major within the tile
  /// (those past the image's right or bottom edge are left black), adds its rays to
  /// `counts`, and records its calls to the backend in `log` when one is given. Thread-safe
  /// (each thread with its own `scratch`).
  void render(int index, std::span<Vec3f, kTilePixels> pixels, TileCounts& counts, Scratch& scratch,
              std::vector<TraceLog::Call>* log = nullptr) const;
  /// Copies the part of tile `index`'s `pixels` that lies inside the image into `image`
  /// (settings' size, rgb allocated).
  void place(int index, std::span<const Vec3f, kTilePixels> pixels, Image& image) const;
  /// The statistics of a render whose tiles traced `counts` in `seconds`.
  RenderStats stats(const TileCounts& counts, double seconds) const;

 private:
  struct Impl;
  std::unique_ptr<const Impl> impl_;
};

/// Renders `scene` as seen by `camera` (camera.width()/height() must equal settings'),
/// tracing with `backend`; when `log` is given, records every call made to the backend. The result depends only on the inputs, never on thread count.
/// Throws rp::Error for settings out of range (spp < 1, a non-square spp for the uniform
/// sampler, adaptive depth outside 0..8, a negative threshold).
/// Called from worker threads with the fraction of tiles done, in (0, 1]; must be thread-safe.
using ProgressFn = std::function<void(double fraction)>;

RenderResult render(const Scene& scene, const Backend& backend, const Camera& camera,
                    const RenderSettings& settings, const ProgressFn& progress = {}, TraceLog* log = nullptr);

/// Makes the calls of `log` again through `backend`, as the render made them (tiles in
/// parallel, each tile's calls in order), and returns the seconds they took: the render's
/// trace time alone.
double replay_traces(const TraceLog& log, const Backend& backend);

/// Arbitrary output variables of the primary hit through each pixel centre, row-major from
/// the top row. A pixel whose ray misses has depth +inf, zero normals and barycentrics,
/// prim_id kInvalidId and instance_id kNoInstance.
struct Aovs {
  int width = 0, height = 0;
  std::vector<float> depth;           ///< hit distance along the (unit) camera ray
  std::vector<float> normal;          ///< geometric normal, unit, face-forwarded; 3 per pixel
  std::vector<float> shading_normal;  ///< interpolated normal where the mesh has them; 3 per pixel
  std::vector<float> uv;              ///< barycentrics (u, v); 2 per pixel
  std::vector<uint32_t> prim_id;
  std::vector<uint32_t> instance_id;  ///< Hit::instance_id (kNoInstance: none)
};

/// The AOVs of `scene` through `camera`, traced in 4x2 packets with all threads.
Aovs render_aovs(const Scene& scene, const Backend& backend, const Camera& camera);

/// Sample position in [0, 1)^2 for sample s of a pixel under `sampler` (uniform, random or
/// stratified), from a counter-based hash of (seed, pixel, sample) so every pixel's stream
/// is independent of scheduling. spp == 1 is the pixel centre for every sampler but random.
Vec2f pixel_sample(uint64_t seed, uint64_t pixel, int sample, int spp, Sampler sampler = Sampler::stratified);

/// Lens position in [0, 1)^2 for sample s of a pixel (thin-lens cameras), from a stream
/// independent of pixel_sample's.
Vec2f lens_sample(uint64_t seed, uint64_t pixel, int sample);

/// Fresnel reflectance of a smooth dielectric for unpolarised light (exact form), for a
/// direction whose cosine with the normal is cos_i, from a medium of index n1 into n2; 1 on
/// total internal reflection.
float fresnel_dielectric(float cos_i, float n1, float n2);

}  // namespace rp
