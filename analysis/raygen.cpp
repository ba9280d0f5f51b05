#include "analysis/raygen.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "base/error.h"
#include "base/offset.h"
#include "render/camera.h"

namespace rp {

RaySet primary_rays(const Scene& scene, int width, int height) {
  const Camera cam(scene.camera().value_or(frame_bounds(scene.bounds(), scene.up_axis())), width, height);
  RaySet rs;
  rs.width = width;
  rs.height = height;
  rs.rays.reserve(size_t(width) * height);
  rs.pixel.reserve(size_t(width) * height);
  for (int ty = 0; ty < height; ty += kPrimaryTile)
    for (int tx = 0; tx < width; tx += kPrimaryTile)
      for (int b = 0; b < kPrimaryTile * kPrimaryTile / 8; ++b) {
        const TileBlock block = tile_block(b);
        for (int lane = 0; lane < 8; ++lane) {
          const int px = tx + block.x + lane % 4, py = ty + block.y + lane / 4;
          if (px >= width || py >= height) continue;
          rs.rays.push_back(cam.generate(float(px) + 0.5f, float(py) + 0.5f));
          rs.pixel.push_back(uint32_t(py) * uint32_t(width) + uint32_t(px));
        }
      }
  return rs;
}

namespace {

/// The face-forwarded geometric normal and the offset origin of a hit.
struct Leaving {
  Vec3f origin, normal;
};
Leaving leave(const Scene& scene, const Ray& ray, const Hit& hit) {
  const SurfacePoint sp = scene.surface(ray, hit);
  const Vec3f n = dot(sp.geometric_normal, ray.dir) < 0.0f ? sp.geometric_normal : -sp.geometric_normal;
  return {offset_ray_origin(sp.position, n), n};
}

RaySet derived(const RaySet& primary) {
  RaySet rs;
  rs.width = primary.width;
  rs.height = primary.height;
  return rs;
}

}  // namespace

RaySet shadow_rays(const Scene& scene, const RaySet& primary, std::span<const Hit> hits) {
  RP_CHECK(hits.size() == primary.rays.size(), "shadow_rays: ", hits.size(), " hits for ", primary.rays.size(), " rays");
  const Box3f b = scene.bounds();
  const Vec3f light = !scene.point_lights().empty() ? scene.point_lights()[0].position
                      : b.empty()                   ? Vec3f{0.0f, 10.0f, 0.0f}
                                                    : b.center() + Vec3f{0.0f, 2.0f * length(b.extent()), 0.0f};
  RaySet rs = derived(primary);
  for (size_t i = 0; i < hits.size(); ++i) {
    if (!hits[i].hit()) continue;
    const Leaving l = leave(scene, primary.rays[i], hits[i]);
    rs.rays.push_back({l.origin, 0.0f, light - l.origin, 1.0f - 1e-4f});
    if (!primary.pixel.empty()) rs.pixel.push_back(primary.pixel[i]);
  }
  return rs;
}

RaySet diffuse_rays(const Scene& scene, const RaySet& primary, std::span<const Hit> hits, uint64_t seed) {
  RP_CHECK(hits.size() == primary.rays.size(), "diffuse_rays: ", hits.size(), " hits for ", primary.rays.size(), " rays");
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  RaySet rs = derived(primary);
  for (size_t i = 0; i < hits.size(); ++i) {
    if (!hits[i].hit()) continue;
    const Leaving l = leave(scene, primary.rays[i], hits[i]);
    // Cosine-weighted hemisphere by Malley's method: a uniform disk point lifted to the hemisphere.
    const float r = std::sqrt(u01(rng)), phi = 2.0f * float(kPi) * u01(rng);
    const Basis<float> tb = orthonormal_basis(l.normal);
    const Vec3f d = tb.t * (r * std::cos(phi)) + tb.b * (r * std::sin(phi)) +
                    l.normal * std::sqrt(std::max(0.0f, 1.0f - r * r));
    rs.rays.push_back({l.origin, 0.0f, d, std::numeric_limits<float>::infinity()});
    if (!primary.pixel.empty()) rs.pixel.push_back(primary.pixel[i]);
  }
  return rs;
}

RaySet random_rays(const Scene& scene, size_t count, uint64_t seed) {
  RP_CHECK(count <= kMaxRandomRays, "random rays: ", count, " is out of range (0..", kMaxRandomRays, ")");
  Box3f b = scene.bounds();
  if (b.empty()) b = Box3f(Vec3f{-1.0f}, Vec3f{1.0f});
  const Vec3f c = b.center();
  const float radius = std::max(length(b.extent()), 1e-6f);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  std::normal_distribution<float> n01(0.0f, 1.0f);
  RaySet rs;
  rs.rays.reserve(count);
  for (size_t i = 0; i < count; ++i) {
    Vec3f on;
    do on = {n01(rng), n01(rng), n01(rng)};
    while (dot(on, on) < 1e-6f);
    const Vec3f org = c + normalize(on) * radius;
    const Vec3f target = b.lo + mul(b.extent(), Vec3f{u01(rng), u01(rng), u01(rng)});
    rs.rays.push_back({org, 0.0f, target - org, std::numeric_limits<float>::infinity()});
  }
  return rs;
}

}  // namespace rp
