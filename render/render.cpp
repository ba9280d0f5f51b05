#include "render/render.h"

#include <tbb/blocked_range2d.h>
#include <tbb/combinable.h>
#include <tbb/concurrent_queue.h>
#include <tbb/parallel_for.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <unordered_map>

#include "base/error.h"
#include "base/offset.h"
#include "render/shade_group.h"
#include "render/shading.h"

namespace rp {

namespace {

constexpr int kTile = kTileSize;

/// splitmix64 finaliser (Steele, Lea, Flood 2014), the per-sample counter hash.
uint64_t mix(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

float to_unit(uint64_t h) { return float(h >> 40) * 0x1.0p-24f; }  // 24 random bits in [0, 1)

/// The per-sample streams of one render: pixel_sample and lens_sample with what does not
/// depend on the pixel and the sample (the seed's hash, the stratification grid) worked out
/// once; the same values. A sample's hash is mix(key ^ sample) of its pixel's key, so a
/// tile works its pixels' keys out once for all its samples (pixel_key, lens_key), and each
/// sample's stratum once for all its pixels (stratum).
struct SampleStreams {
  uint64_t pixel_seed, lens_seed;
  int spp, grid;  ///< grid: the side of the largest square of strata, sqrt(spp) rounded down
  Sampler sampler;

  SampleStreams(uint64_t seed, int spp_, Sampler s)
      : pixel_seed(mix(seed ^ 0x9e3779b97f4a7c15ull)), lens_seed(mix(seed ^ 0x5851f42d4c957f2dull)), spp(spp_),
        grid(int(std::sqrt(double(spp_)))), sampler(s) {}

  /// Sample `sample`'s cell of the grid, and whether it lies past the grid (a free sample).
  struct Stratum {
    int sample, x, y;
    bool free;
  };
  Stratum stratum(int sample) const { return {sample, sample % grid, sample / grid, sample >= grid * grid}; }

  uint64_t pixel_key(uint64_t pixel) const { return mix(pixel_seed ^ pixel); }
  uint64_t lens_key(uint64_t pixel) const { return mix(lens_seed ^ pixel); }

  /// Where sample `s` lies in its pixel, the pixel's hashed position (jx, jy) aside: the
  /// centre of its grid cell (uniform), the pixel centre (one sample), or (jx, jy) itself
  /// (random, or past the grid) or placed in its cell (stratified).
  enum class Place { cell_centre, pixel_centre, jitter, in_cell };
  Place place(const Stratum& s) const {
    if (sampler == Sampler::uniform) return Place::cell_centre;
    if (sampler == Sampler::random) return Place::jitter;
    if (spp == 1) return Place::pixel_centre;
    return s.free ? Place::jitter : Place::in_cell;
  }
  static Vec2f jitter(uint64_t key, int sample) {
    const uint64_t h = mix(key ^ uint64_t(sample));
    return {to_unit(h), to_unit(mix(h))};
  }

  Vec2f pixel(uint64_t key, const Stratum& s) const {
    float x[1], y[1];
    pixels<1>(&key, s, x, y);
    return {x[0], y[0]};
  }
  /// pixel() of N pixels (their keys) at once: the hashes a pixel at a time, the rest in
  /// loops over the pixels with one operation each, which the compiler vectorises (the same
  /// IEEE operations, so the same values).
  template <int N>
  void pixels(const uint64_t* keys, const Stratum& s, float* x, float* y) const {
    const Place at = place(s);
    if (at == Place::cell_centre || at == Place::pixel_centre) {
      const float g = at == Place::cell_centre ? float(grid) : 1.0f;
      const float cx = at == Place::cell_centre ? float(s.x) : 0.0f, cy = at == Place::cell_centre ? float(s.y) : 0.0f;
      for (int k = 0; k < N; ++k) {
        x[k] = (cx + 0.5f) / g;
        y[k] = (cy + 0.5f) / g;
      }
      return;
    }
    for (int k = 0; k < N; ++k) {
      const Vec2f j = jitter(keys[k], s.sample);
      x[k] = j.x;
      y[k] = j.y;
    }
    if (at == Place::jitter) return;
    const float g = float(grid), cx = float(s.x), cy = float(s.y);
    for (int k = 0; k < N; ++k) {
      x[k] = (cx + x[k]) / g;
      y[k] = (cy + y[k]) / g;
    }
  }
  Vec2f lens(uint64_t key, int sample) const { return jitter(key, sample); }
};

struct Counters {
  uint64_t shadow = 0, reflection = 0, refraction = 0;
};

/// The backend as the renderer calls it, recording each call when the render is logged.
struct Tracer {
  const Backend& backend;
  std::vector<TraceLog::Call>* log = nullptr;  ///< this tile's calls, or none
  void intersect(std::span<const Ray> rays, std::span<Hit> hits, Coherence c) const {
    if (log) log->push_back({false, c, std::vector<Ray>(rays.begin(), rays.end())});
    backend.intersect(rays, hits, c);
  }
  void occluded(std::span<const Ray> rays, std::span<uint8_t> out, Coherence c) const {
    if (log) log->push_back({true, c, std::vector<Ray>(rays.begin(), rays.end())});
    backend.occluded(rays, out, c);
  }
};

/// A thread's scratch (TileRenderer::Scratch), reused from tile to tile and batch to batch:
/// its arrays keep their size.
struct ShadeWork {
  /// A batch's first rays and paths (a tile's primary rays, kept for all its samples), then
  /// each bounce's.
  std::vector<Ray> primary, rays, next_rays;
  std::vector<PathState> primary_paths;
  std::vector<Vec2f> lens;  ///< a tile's lens positions (thin lens; adaptive sampling: every camera)
  std::vector<Hit> hits;
  std::vector<uint8_t> occluded;
  std::vector<PathState> paths, next_paths;
  /// Per light: the shadow rays of this batch, and the lit contributions waiting for them.
  /// Rays towards one light from one tile share an endpoint (or, for a directional light, a
  /// direction) and go to the backend as one coherent span.
  std::vector<ShadowQueue> shadow;
  std::vector<BounceHit> bounces;
};

/// The mirror and glass bounces of hit `b` (whose path is `ps`): mirror reflection and
/// refraction (Whitted 1980) with the exact dielectric Fresnel term, each a ray of the next
/// batch when its weight is not zero.
void bounce(const Scene& scene, const BounceHit& b, const PathState& ps, ShadeWork& w, Counters& n) {
  constexpr float inf = std::numeric_limits<float>::infinity();
  const Material& m = scene.materials()[b.material];
  const Vec3f d = b.d, ng = b.ng;
  const float transparency = 1.0f - m.opacity;
  // Fresnel on the geometric normal: entering when the ray met the front face.
  const float cos_i = -dot(d, ng);
  const float n1 = b.back ? m.ior : 1.0f, n2 = b.back ? 1.0f : m.ior;
  const float fresnel = transparency > 0.0f ? fresnel_dielectric(cos_i, n1, n2) : 0.0f;
  const Vec3f reflect_weight = m.specular * m.mirror + Vec3f(transparency * fresnel);
  if (max_component(reflect_weight) > 0.0f) {
    w.next_rays.push_back({b.origin, 0.0f, d + ng * (2.0f * cos_i), inf});
    w.next_paths.push_back({ps.slot, mul(ps.weight, reflect_weight)});
    ++n.reflection;
  }
  const float transmit = transparency * (1.0f - fresnel);
  if (transmit > 0.0f) {
    // Refraction rays leave to the far side of the surface.
    const float eta = n1 / n2;
    const float cos_t = std::sqrt(std::max(0.0f, 1.0f - eta * eta * (1.0f - cos_i * cos_i)));
    w.next_rays.push_back({offset_ray_origin(b.position, -ng), 0.0f, d * eta + ng * (eta * cos_i - cos_t), inf});
    w.next_paths.push_back({ps.slot, ps.weight * transmit});
    ++n.refraction;
  }
}

/// Shades the primary rays `primary` / `primary_paths` (whose groups of 8 are packets), adding each
/// path's radiance to out[slot]: Blinn-Phong with shadow rays through occluded(), then the
/// bounces, up to max_depth, traced as incoherent batches. The per-hit work is the batch
/// shader's (shade_group.h: 8 hits at a time where the CPU allows).
void shade(const ShadeScene& scene, const Tracer& backend, ShadeBatchFn shade_batch, int max_depth,
           std::span<const Ray> primary, std::span<const PathState> primary_paths, ShadeWork& w, std::span<Vec3f> out,
           Counters& n) {
  const size_t n_lights = scene.shadow_tfar.size();
  w.shadow.resize(n_lights);
  std::span<const Ray> rays = primary;
  std::span<const PathState> paths = primary_paths;
  for (int depth = 0; !rays.empty(); ++depth) {
    const Coherence coherence = depth == 0 ? Coherence::coherent : Coherence::incoherent;
    w.hits.resize(rays.size());
    backend.intersect(rays, w.hits, coherence);
    for (ShadowQueue& q : w.shadow) q.reset(rays.size());
    w.bounces.clear();
    ShadeOut sink{out, w.shadow, w.bounces};
    shade_batch(scene, rays, w.hits, paths, depth < max_depth, sink);
    w.next_rays.clear();
    w.next_paths.clear();
    for (const BounceHit& b : w.bounces) bounce(scene.scene, b, paths[b.ray], w, n);
    // Contributions are added light by light, in batch order: a fixed order for the tile,
    // whatever the thread count.
    for (size_t l = 0; l < n_lights; ++l) {
      const ShadowQueue& q = w.shadow[l];
      if (!q.count) continue;
      w.occluded.resize(q.count);
      backend.occluded(q.batch_rays(), w.occluded, coherence);
      n.shadow += q.count;
      const std::span<const Pending> pending = q.batch_pending();
      for (size_t k = 0; k < pending.size(); ++k)
        if (!w.occluded[k]) out[pending[k].slot] += pending[k].contribution;
    }
    std::swap(w.rays, w.next_rays);
    std::swap(w.paths, w.next_paths);
    rays = w.rays;
    paths = w.paths;
  }
}

/// Renders the tile at (x0, y0) with one of the per-sample samplers into `tile` (kTile^2 colours, zero).
uint64_t sample_tile(const ShadeScene& scene, const Tracer& backend, ShadeBatchFn shade_batch, const Camera& camera,
                     const RenderSettings& st, int x0, int y0, ShadeWork& w, std::span<Vec3f> tile, Counters& n) {
  uint64_t primary = 0;
  const SampleStreams streams(st.seed, st.spp, st.sampler);
  const bool thin_lens = camera.model() == CameraModel::thin_lens, pinhole = camera.model() == CameraModel::pinhole;
  // Each lane's pixel (clamped to the image: lanes past it are traced as invalid rays), its
  // keys and its path (its pixel's slot, or none past the image), in the tile's 4x2-block
  // order, for all the samples. A pinhole ray is valid by construction (the camera checked its
  // eye; its direction is unit length), so its paths hold for every sample; other cameras'
  // rays are checked per sample below.
  uint64_t pixel_keys[kTile * kTile], lens_keys[kTile * kTile];
  float base_x[kTile * kTile], base_y[kTile * kTile];
  uint32_t slots[kTile * kTile];  // the slot a lane's path takes when its ray is valid
  w.primary.resize(kTile * kTile);
  w.primary_paths.resize(kTile * kTile);
  if (thin_lens) w.lens.resize(kTile * kTile);
  bool partial = false;  // some lane lies past the image
  for (int by = 0, at = 0; by < kTile; by += 2)
    for (int bx = 0; bx < kTile; bx += 4)
      for (int lane = 0; lane < 8; ++lane, ++at) {
        const int lx = bx + lane % 4, ly = by + lane / 4;
        const int x = std::min(x0 + lx, st.width - 1), y = std::min(y0 + ly, st.height - 1);
        const uint64_t pixel = uint64_t(y) * uint64_t(st.width) + uint64_t(x);
        pixel_keys[at] = streams.pixel_key(pixel);
        if (thin_lens) lens_keys[at] = streams.lens_key(pixel);
        base_x[at] = float(x);
        base_y[at] = float(y);
        const bool inside = x0 + lx < st.width && y0 + ly < st.height;
        slots[at] = inside ? uint32_t(ly * kTile + lx) : kInvalidId;
        w.primary_paths[size_t(at)] = inside ? PathState{slots[at], Vec3f{1.0f}} : PathState{kInvalidId, {}};
        partial = partial || !inside;
        primary += uint64_t(pinhole && inside) * uint64_t(st.spp);
      }
  for (int s = 0; s < st.spp; ++s) {
    const SampleStreams::Stratum stratum = streams.stratum(s);
    // Primary rays: 4x2 blocks, lane = x + 4y, so every group of 8 is one packet. The tile's
    // image positions are all worked out before its rays (the camera's vector loads of them
    // then read stores long done, not the last few, which no store can forward to them).
    constexpr size_t kLanes = kTile * kTile;
    float px[kLanes], py[kLanes];
    streams.pixels<int(kLanes)>(pixel_keys, stratum, px, py);
    for (size_t k = 0; k < kLanes; ++k) {
      px[k] += base_x[k];
      py[k] += base_y[k];
    }
    if (thin_lens)
      for (size_t k = 0; k < kLanes; ++k) w.lens[k] = streams.lens(lens_keys[k], s);
    camera.generate_rays(px, py, thin_lens ? w.lens.data() : nullptr, w.primary);
    if (!pinhole || partial)
      for (size_t k = 0; k < kLanes; ++k) {
        Ray& r = w.primary[k];
        if (slots[k] == kInvalidId) {
          r = {{}, 1.0f, {1.0f, 0.0f, 0.0f}, 0.0f};  // past the image: invalid, traced as a miss
          continue;
        }
        if (pinhole) continue;
        // No ray (outside a fisheye's image circle): the pixel stays black.
        const bool valid = valid_ray(r);
        w.primary_paths[k].slot = valid ? slots[k] : kInvalidId;
        primary += valid;
      }
    shade(scene, backend, shade_batch, st.max_depth, w.primary, w.primary_paths, w, tile, n);
  }
  const float inv = 1.0f / float(st.spp);
  for (Vec3f& c : tile) c *= inv;
  return primary;
}

/// The lecture notes' adaptive sampling for the tile at (x0, y0): colours at the pixel-grid corners;
/// a cell whose four corner colours differ by more than the threshold (in any channel) is
/// split into four, which needs the midpoints of its edges and its centre, down to cells of
/// 1/2^depth pixel; a pixel is the area-weighted mean of its cells' corner averages. Corner
/// positions are integers on the finest grid, shared between neighbouring cells through a
/// cache, so each point is traced once per tile.
uint64_t adaptive_tile(const ShadeScene& scene, const Tracer& backend, ShadeBatchFn shade_batch, const Camera& camera,
                       const RenderSettings& st, int x0, int y0, ShadeWork& w, std::span<Vec3f> tile, Counters& n) {
  const int scale = 1 << st.adaptive_depth;
  const int tw = std::min(kTile, st.width - x0), th = std::min(kTile, st.height - y0);
  auto key = [](int64_t x, int64_t y) { return uint64_t(x) << 32 | uint64_t(uint32_t(y)); };
  std::unordered_map<uint64_t, Vec3f> colour;
  std::vector<std::pair<int, int>> wanted;
  std::vector<Vec3f> shaded;
  uint64_t primary = 0;
  auto want = [&](int x, int y) {
    if (colour.emplace(key(x, y), Vec3f{}).second) wanted.push_back({x, y});
  };
  std::vector<float> px, py;
  auto trace_wanted = [&] {
    const size_t m = wanted.size();
    px.resize(m);
    py.resize(m);
    w.lens.resize(m);
    for (size_t i = 0; i < m; ++i) {
      const auto [x, y] = wanted[i];
      const uint64_t id = uint64_t(uint32_t(y)) * (uint64_t(st.width) * uint64_t(scale) + 1) + uint64_t(uint32_t(x));
      px[i] = float(x) / float(scale);
      py[i] = float(y) / float(scale);
      w.lens[i] = lens_sample(st.seed, id, 0);
    }
    w.primary.resize(m);
    camera.generate_rays(px, py, w.lens.data(), w.primary);
    w.primary_paths.clear();
    for (size_t i = 0; i < m; ++i) {
      const bool valid = valid_ray(w.primary[i]);
      w.primary_paths.push_back({valid ? uint32_t(i) : kInvalidId, Vec3f{1.0f}});
      primary += valid;
    }
    shaded.assign(wanted.size(), Vec3f{});
    shade(scene, backend, shade_batch, st.max_depth, w.primary, w.primary_paths, w, shaded, n);
    for (size_t i = 0; i < wanted.size(); ++i) colour[key(wanted[i].first, wanted[i].second)] = shaded[i];
    wanted.clear();
  };
  struct Cell {
    int pixel;   ///< local pixel index in the tile
    int x, y;    ///< top-left corner on the finest grid
    int size;    ///< edge on the finest grid
  };
  std::vector<Cell> cells, next;
  for (int ly = 0; ly < th; ++ly)
    for (int lx = 0; lx < tw; ++lx) {
      const int x = (x0 + lx) * scale, y = (y0 + ly) * scale;
      cells.push_back({ly * kTile + lx, x, y, scale});
      want(x, y);
      want(x + scale, y);
      want(x, y + scale);
      want(x + scale, y + scale);
    }
  trace_wanted();
  while (!cells.empty()) {
    next.clear();
    for (const Cell& c : cells) {
      const Vec3f a = colour[key(c.x, c.y)], b = colour[key(c.x + c.size, c.y)];
      const Vec3f d = colour[key(c.x, c.y + c.size)], e = colour[key(c.x + c.size, c.y + c.size)];
      const Vec3f lo = min(min(a, b), min(d, e)), hi = max(max(a, b), max(d, e));
      if (c.size > 1 && max_component(hi - lo) > st.adaptive_threshold) {
        const int h = c.size / 2;
        want(c.x + h, c.y);
        want(c.x, c.y + h);
        want(c.x + h, c.y + h);
        want(c.x + c.size, c.y + h);
        want(c.x + h, c.y + c.size);
        for (int k = 0; k < 4; ++k) next.push_back({c.pixel, c.x + (k % 2) * h, c.y + (k / 2) * h, h});
      } else {
        const float area = float(c.size) * float(c.size) / (float(scale) * float(scale));
        tile[size_t(c.pixel)] += (a + b + d + e) * (0.25f * area);
      }
    }
    trace_wanted();
    std::swap(cells, next);
  }
  return primary;
}

}  // namespace

Vec2f pixel_sample(uint64_t seed, uint64_t pixel, int sample, int spp, Sampler sampler) {
  const SampleStreams s(seed, spp, sampler);
  return s.pixel(s.pixel_key(pixel), s.stratum(sample));
}

Vec2f lens_sample(uint64_t seed, uint64_t pixel, int sample) {
  const SampleStreams s(seed, 1, Sampler::random);
  return s.lens(s.lens_key(pixel), sample);
}

float fresnel_dielectric(float cos_i, float n1, float n2) {
  cos_i = std::clamp(cos_i, 0.0f, 1.0f);
  const float eta = n1 / n2;
  const float sin2_t = eta * eta * (1.0f - cos_i * cos_i);
  if (sin2_t >= 1.0f) return 1.0f;  // total internal reflection
  const float cos_t = std::sqrt(1.0f - sin2_t);
  const float r_perp = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
  const float r_par = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t);
  return 0.5f * (r_perp * r_perp + r_par * r_par);
}

TileCounts& TileCounts::operator+=(const TileCounts& o) {
  primary += o.primary;
  shadow += o.shadow;
  reflection += o.reflection;
  refraction += o.refraction;
  return *this;
}

struct TileRenderer::Impl {
  const Backend& backend;
  const Camera& camera;
  RenderSettings settings;
  ShadeScene shade_scene;
  ShadeBatchFn shade_batch;
  int tiles_x, tiles_y;
};

TileRenderer::TileRenderer(const Scene& scene, const Backend& backend, const Camera& camera, const RenderSettings& st) {
  RP_CHECK(camera.width() == st.width && camera.height() == st.height, "render: camera resolution ",
           camera.width(), "x", camera.height(), " differs from settings ", st.width, "x", st.height);
  RP_CHECK(st.spp >= 1 && st.spp <= kMaxSpp, "render: spp ", st.spp, " is out of range (1..", kMaxSpp, ")");
  RP_CHECK(st.max_depth >= 0, "render: max depth ", st.max_depth, " must be >= 0");
  if (st.sampler == Sampler::uniform) {
    const int m = int(std::sqrt(double(st.spp)));
    RP_CHECK(m * m == st.spp, "render: the uniform sampler needs a square spp (1, 4, 9, ...), got ", st.spp);
  }
  RP_CHECK(st.adaptive_depth >= 0 && st.adaptive_depth <= 8, "render: adaptive depth ", st.adaptive_depth,
           " must be in 0..8");
  RP_CHECK(st.adaptive_threshold >= 0.0f, "render: adaptive threshold ", st.adaptive_threshold, " must be >= 0");
  impl_.reset(new Impl{backend, camera, st, ShadeScene(scene), shade_batch_function(), (st.width + kTile - 1) / kTile,
                       (st.height + kTile - 1) / kTile});
}

TileRenderer::~TileRenderer() = default;

const RenderSettings& TileRenderer::settings() const { return impl_->settings; }
int TileRenderer::tiles_x() const { return impl_->tiles_x; }
int TileRenderer::tiles_y() const { return impl_->tiles_y; }

struct TileRenderer::Scratch::Work : ShadeWork {};
TileRenderer::Scratch::Scratch() : work_(new Work) {}
TileRenderer::Scratch::~Scratch() = default;

void TileRenderer::render(int index, std::span<Vec3f, kTilePixels> pixels, TileCounts& counts, Scratch& scratch,
                          std::vector<TraceLog::Call>* log) const {
  const Impl& m = *impl_;
  const Tracer tracer{m.backend, log};
  ShadeWork& w = *scratch.work_;
  Counters n;
  const int x0 = index % m.tiles_x * kTile, y0 = index / m.tiles_x * kTile;
  std::fill(pixels.begin(), pixels.end(), Vec3f{});
  counts.primary += m.settings.sampler == Sampler::adaptive
                        ? adaptive_tile(m.shade_scene, tracer, m.shade_batch, m.camera, m.settings, x0, y0, w, pixels, n)
                        : sample_tile(m.shade_scene, tracer, m.shade_batch, m.camera, m.settings, x0, y0, w, pixels, n);
  counts.shadow += n.shadow;
  counts.reflection += n.reflection;
  counts.refraction += n.refraction;
}

void TileRenderer::place(int index, std::span<const Vec3f, kTilePixels> pixels, Image& image) const {
  const Impl& m = *impl_;
  const int x0 = index % m.tiles_x * kTile, y0 = index / m.tiles_x * kTile;
  for (int ly = 0; ly < kTile && y0 + ly < image.height; ++ly)
    for (int lx = 0; lx < kTile && x0 + lx < image.width; ++lx) {
      const Vec3f c = pixels[size_t(ly * kTile + lx)];
      float* out = &image.rgb[(size_t(y0 + ly) * size_t(image.width) + size_t(x0 + lx)) * 3];
      out[0] = c.x;
      out[1] = c.y;
      out[2] = c.z;
    }
}

RenderStats TileRenderer::stats(const TileCounts& counts, double seconds) const {
  const RenderSettings& st = impl_->settings;
  RenderStats s;
  s.primary = counts.primary;
  s.shadow = counts.shadow;
  s.reflection = counts.reflection;
  s.refraction = counts.refraction;
  const uint64_t scale = st.sampler == Sampler::adaptive ? (uint64_t(1) << st.adaptive_depth) : 1;
  s.uniform_primary = st.sampler == Sampler::adaptive
                          ? (uint64_t(st.width) * scale + 1) * (uint64_t(st.height) * scale + 1)
                          : uint64_t(st.width) * uint64_t(st.height) * uint64_t(st.spp);
  s.seconds = seconds;
  return s;
}

RenderResult render(const Scene& scene, const Backend& backend, const Camera& camera, const RenderSettings& st,
                    const ProgressFn& progress, TraceLog* log) {
  const TileRenderer tiles(scene, backend, camera, st);
  const auto start = std::chrono::steady_clock::now();
  RenderResult result;
  Image& img = result.image;
  img.width = st.width;
  img.height = st.height;
  img.rgb.assign(size_t(st.width) * st.height * 3, 0.0f);
  const int n_tiles = tiles.tile_count();
  if (log) log->tiles.assign(size_t(n_tiles), {});
  tbb::combinable<TileCounts> counts;
  // The threads' working memory, reused from one range of tiles to the next: taken from a
  // pool and given back, so that no two calls share one even on one thread.
  tbb::concurrent_queue<std::unique_ptr<TileRenderer::Scratch>> scratches;
  std::atomic<int> tiles_done{0};
  tbb::parallel_for(tbb::blocked_range2d<int>(0, tiles.tiles_y(), 1, 0, tiles.tiles_x(), 1),
                    [&](const tbb::blocked_range2d<int>& r) {
                      std::array<Vec3f, kTilePixels> pixels;
                      std::unique_ptr<TileRenderer::Scratch> scratch;
                      if (!scratches.try_pop(scratch)) scratch = std::make_unique<TileRenderer::Scratch>();
                      for (int ty = r.rows().begin(); ty < r.rows().end(); ++ty)
                        for (int tx = r.cols().begin(); tx < r.cols().end(); ++tx) {
                          const int index = ty * tiles.tiles_x() + tx;
                          tiles.render(index, pixels, counts.local(), *scratch,
                                       log ? &log->tiles[size_t(index)] : nullptr);
                          tiles.place(index, pixels, img);
                          const int done = ++tiles_done;
                          if (progress) progress(double(done) / double(n_tiles));
                        }
                      scratches.push(std::move(scratch));
                    });
  TileCounts total;
  counts.combine_each([&](const TileCounts& c) { total += c; });
  result.stats = tiles.stats(total, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  return result;
}

uint64_t TraceLog::rays() const {
  uint64_t n = 0;
  for (const auto& tile : tiles)
    for (const Call& c : tile) n += c.rays.size();
  return n;
}

double replay_traces(const TraceLog& log, const Backend& backend) {
  const auto start = std::chrono::steady_clock::now();
  tbb::parallel_for(size_t(0), log.tiles.size(), [&](size_t t) {
    std::vector<Hit> hits;
    std::vector<uint8_t> occluded;
    for (const TraceLog::Call& c : log.tiles[t]) {
      if (c.any) {
        occluded.resize(c.rays.size());
        backend.occluded(c.rays, occluded, c.coherence);
      } else {
        hits.resize(c.rays.size());
        backend.intersect(c.rays, hits, c.coherence);
      }
    }
  });
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

Aovs render_aovs(const Scene& scene, const Backend& backend, const Camera& camera) {
  const int w = camera.width(), h = camera.height();
  Aovs a;
  a.width = w;
  a.height = h;
  const size_t n = size_t(w) * size_t(h);
  a.depth.assign(n, std::numeric_limits<float>::infinity());
  a.normal.assign(3 * n, 0.0f);
  a.shading_normal.assign(3 * n, 0.0f);
  a.uv.assign(2 * n, 0.0f);
  a.prim_id.assign(n, kInvalidId);
  a.instance_id.assign(n, kNoInstance);
  const int tiles_x = (w + kTile - 1) / kTile, tiles_y = (h + kTile - 1) / kTile;
  tbb::parallel_for(tbb::blocked_range2d<int>(0, tiles_y, 1, 0, tiles_x, 1), [&](const tbb::blocked_range2d<int>& r) {
    std::vector<Ray> rays;
    std::vector<uint32_t> pixel;
    std::vector<Hit> hits;
    for (int ty = r.rows().begin(); ty < r.rows().end(); ++ty)
      for (int tx = r.cols().begin(); tx < r.cols().end(); ++tx) {
        rays.clear();
        pixel.clear();
        for (int by = 0; by < kTile; by += 2)
          for (int bx = 0; bx < kTile; bx += 4)
            for (int lane = 0; lane < 8; ++lane) {
              const int x = tx * kTile + bx + lane % 4, y = ty * kTile + by + lane / 4;
              const bool inside = x < w && y < h;
              rays.push_back(inside ? camera.generate(float(x) + 0.5f, float(y) + 0.5f)
                                    : Ray{{}, 1.0f, {1.0f, 0.0f, 0.0f}, 0.0f});
              pixel.push_back(inside ? uint32_t(y) * uint32_t(w) + uint32_t(x) : kInvalidId);
            }
        hits.resize(rays.size());
        backend.intersect(rays, hits, Coherence::coherent);
        for (size_t i = 0; i < rays.size(); ++i) {
          if (pixel[i] == kInvalidId || !hits[i].hit()) continue;
          const size_t p = pixel[i];
          const SurfacePoint sp = scene.surface(rays[i], hits[i]);
          const bool back = dot(sp.geometric_normal, rays[i].dir) > 0.0f;
          const Vec3f ng = back ? -sp.geometric_normal : sp.geometric_normal;
          const Vec3f ns = back ? -sp.shading_normal : sp.shading_normal;
          a.depth[p] = hits[i].t * length(rays[i].dir);
          for (int c = 0; c < 3; ++c) {
            a.normal[3 * p + size_t(c)] = ng[c];
            a.shading_normal[3 * p + size_t(c)] = ns[c];
          }
          a.uv[2 * p] = hits[i].u;
          a.uv[2 * p + 1] = hits[i].v;
          a.prim_id[p] = hits[i].prim_id;
          a.instance_id[p] = hits[i].instance_id;
        }
      }
  });
  return a;
}

}  // namespace rp

