#include "engine/render.h"

#include <tbb/blocked_range2d.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <chrono>
#include <cmath>

#include "engine/error.h"
#include "engine/offset.h"

namespace rp {

namespace {

constexpr int kTile = 16;  ///< tile edge in pixels; a tile holds 32 packets of 4x2 pixels

/// splitmix64 finaliser (Steele, Lea, Flood 2014), the per-sample counter hash.
uint64_t mix(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

float to_unit(uint64_t h) { return float(h >> 40) * 0x1.0p-24f; }  // 24 random bits in [0, 1)

Vec3f sky(const Vec3f& dir) {
  const float t = 0.5f * (normalize(dir).y + 1.0f);
  return Vec3f{0.85f, 0.88f, 0.92f} * (1.0f - t) + Vec3f{0.35f, 0.55f, 0.85f} * t;
}

/// One ray still being followed: the pixel it adds to and the weight it carries.
struct PathState {
  uint32_t pixel;  ///< index into the tile's accumulator
  Vec3f weight;
};

/// Per-tile scratch, allocated once per tile (never per ray).
struct TileWork {
  std::vector<Ray> rays, shadow_rays, next_rays;
  std::vector<Hit> hits;
  std::vector<uint8_t> occluded;
  std::vector<PathState> paths, next_paths;
  struct Pending { uint32_t pixel; Vec3f contribution; };
  std::vector<Pending> pending;  ///< lit contributions waiting for their shadow ray
  std::vector<Vec3f> accum;
};

}  // namespace

Vec2f pixel_sample(uint64_t seed, uint64_t pixel, int sample, int spp) {
  const uint64_t h = mix(mix(mix(seed ^ 0x9e3779b97f4a7c15ull) ^ pixel) ^ uint64_t(sample));
  const float jx = to_unit(h), jy = to_unit(mix(h));
  if (spp == 1) return {0.5f, 0.5f};
  const int m = int(std::sqrt(double(spp)));
  if (sample >= m * m) return {jx, jy};
  return {(float(sample % m) + jx) / float(m), (float(sample / m) + jy) / float(m)};
}

Vec2f lens_sample(uint64_t seed, uint64_t pixel, int sample) {
  const uint64_t h = mix(mix(mix(seed ^ 0x5851f42d4c957f2dull) ^ pixel) ^ uint64_t(sample));
  return {to_unit(h), to_unit(mix(h))};
}

RenderResult render(const Scene& scene, const Backend& backend, const Camera& camera,
                    const RenderSettings& st) {
  RP_CHECK(camera.width() == st.width && camera.height() == st.height, "render: camera resolution ",
           camera.width(), "x", camera.height(), " differs from settings ", st.width, "x", st.height);
  RP_CHECK(st.spp >= 1, "render: spp ", st.spp, " must be >= 1");
  RP_CHECK(st.max_depth >= 0, "render: max depth ", st.max_depth, " must be >= 0");
  const auto start = std::chrono::steady_clock::now();
  RenderResult result;
  Image& img = result.image;
  img.width = st.width;
  img.height = st.height;
  img.rgb.assign(size_t(st.width) * st.height * 3, 0.0f);
  std::atomic<uint64_t> n_primary{0}, n_shadow{0}, n_reflection{0};
  const auto& materials = scene.materials();
  const int tiles_x = (st.width + kTile - 1) / kTile, tiles_y = (st.height + kTile - 1) / kTile;

  auto shade_tile = [&](int tx, int ty) {
    TileWork w;
    w.accum.assign(kTile * kTile, Vec3f{});
    const int x0 = tx * kTile, y0 = ty * kTile;
    uint64_t primary = 0, shadow = 0, reflection = 0;
    for (int s = 0; s < st.spp; ++s) {
      // Primary rays: 4x2 blocks, lane = x + 4y, so every group of 8 is one packet.
      w.rays.clear();
      w.paths.clear();
      for (int by = 0; by < kTile; by += 2)
        for (int bx = 0; bx < kTile; bx += 4)
          for (int lane = 0; lane < 8; ++lane) {
            const int lx = bx + lane % 4, ly = by + lane / 4, x = x0 + lx, y = y0 + ly;
            if (x >= st.width || y >= st.height) {
              w.rays.push_back({{}, 1.0f, {1.0f, 0.0f, 0.0f}, 0.0f});  // invalid: traced as a miss
              w.paths.push_back({kInvalidId, {}});
              continue;
            }
            const uint64_t pixel = uint64_t(y) * uint64_t(st.width) + uint64_t(x);
            const Vec2f j = pixel_sample(st.seed, pixel, s, st.spp);
            const Ray r = camera.generate(float(x) + j.x, float(y) + j.y, lens_sample(st.seed, pixel, s));
            w.rays.push_back(r);
            // No ray (outside a fisheye's image circle): the pixel stays black.
            w.paths.push_back({valid_ray(r) ? uint32_t(ly * kTile + lx) : kInvalidId, Vec3f{1.0f}});
            primary += valid_ray(r);
          }
      for (int depth = 0; !w.rays.empty(); ++depth) {
        const Coherence coherence = depth == 0 ? Coherence::coherent : Coherence::incoherent;
        w.hits.resize(w.rays.size());
        backend.intersect(w.rays, w.hits, coherence);
        w.shadow_rays.clear();
        w.pending.clear();
        w.next_rays.clear();
        w.next_paths.clear();
        for (size_t i = 0; i < w.rays.size(); ++i) {
          const PathState& ps = w.paths[i];
          if (ps.pixel == kInvalidId) continue;
          const Ray& ray = w.rays[i];
          const Hit& hit = w.hits[i];
          if (!hit.hit()) {
            w.accum[ps.pixel] += mul(ps.weight, sky(ray.dir));
            continue;
          }
          const SurfacePoint sp = scene.surface(ray, hit);
          const Material& m = materials[sp.material];
          // Face-forward both normals towards the viewer.
          const bool back = dot(sp.geometric_normal, ray.dir) > 0.0f;
          const Vec3f ng = back ? -sp.geometric_normal : sp.geometric_normal;
          Vec3f ns = back ? -sp.shading_normal : sp.shading_normal;
          if (dot(ns, ng) < 0.0f) ns = ng;
          const Vec3f view = -normalize(ray.dir);
          const Vec3f origin = offset_ray_origin(sp.position, ng);
          const float diffuse_weight = 1.0f - m.mirror;
          w.accum[ps.pixel] += mul(ps.weight, m.emission + m.diffuse * (0.06f * diffuse_weight));
          auto light = [&](const Vec3f& to_light, float tfar, const Vec3f& irradiance) {
            const Vec3f l = normalize(to_light);
            const float ndl = dot(ns, l);
            if (ndl <= 0.0f || dot(ng, l) <= 0.0f) return;
            const Vec3f h = normalize(l + view);
            const float spec = std::pow(std::max(0.0f, dot(ns, h)), m.shininess);
            const Vec3f c = mul(m.diffuse * (ndl * diffuse_weight) + m.specular * spec, irradiance);
            w.shadow_rays.push_back({origin, 0.0f, to_light, tfar});
            w.pending.push_back({ps.pixel, mul(ps.weight, c)});
          };
          for (const PointLight& pl : scene.point_lights()) {
            const Vec3f d = pl.position - origin;
            const float r2 = dot(d, d);
            if (r2 > 0.0f) light(d, 1.0f - 1e-4f, pl.intensity / r2);
          }
          for (const DirectionalLight& dl : scene.directional_lights())
            light(-dl.direction, std::numeric_limits<float>::infinity(), dl.irradiance);
          if (m.mirror > 0.0f && depth < st.max_depth) {
            const Vec3f d = normalize(ray.dir);
            const Vec3f r = d - ng * (2.0f * dot(d, ng));
            w.next_rays.push_back({origin, 0.0f, r, std::numeric_limits<float>::infinity()});
            w.next_paths.push_back({ps.pixel, mul(ps.weight, m.specular * m.mirror)});
          }
        }
        if (!w.shadow_rays.empty()) {
          w.occluded.resize(w.shadow_rays.size());
          backend.occluded(w.shadow_rays, w.occluded, coherence);
          shadow += w.shadow_rays.size();
          for (size_t k = 0; k < w.pending.size(); ++k)
            if (!w.occluded[k]) w.accum[w.pending[k].pixel] += w.pending[k].contribution;
        }
        reflection += w.next_rays.size();
        std::swap(w.rays, w.next_rays);
        std::swap(w.paths, w.next_paths);
      }
    }
    const float inv = 1.0f / float(st.spp);
    for (int ly = 0; ly < kTile && y0 + ly < st.height; ++ly)
      for (int lx = 0; lx < kTile && x0 + lx < st.width; ++lx) {
        const Vec3f c = w.accum[ly * kTile + lx] * inv;
        float* out = &img.rgb[(size_t(y0 + ly) * st.width + (x0 + lx)) * 3];
        out[0] = c.x; out[1] = c.y; out[2] = c.z;
      }
    n_primary += primary;
    n_shadow += shadow;
    n_reflection += reflection;
  };

  tbb::parallel_for(tbb::blocked_range2d<int>(0, tiles_y, 1, 0, tiles_x, 1), [&](const tbb::blocked_range2d<int>& r) {
    for (int ty = r.rows().begin(); ty < r.rows().end(); ++ty)
      for (int tx = r.cols().begin(); tx < r.cols().end(); ++tx) shade_tile(tx, ty);
  });
  result.stats = {n_primary.load(), n_shadow.load(), n_reflection.load(),
                  std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()};
  return result;
}

}  // namespace rp
