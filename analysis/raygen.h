#pragma once
/// Ray sets shared by `raypack diff`, `raypack bench`, the tests and the benchmarks: camera rays in
/// 4x2 packets, shadow and diffuse rays from their hits, and random rays around a scene.

#include <cstdint>
#include <span>
#include <vector>

#include "core/backend.h"
#include "core/scene.h"

namespace rp {

/// Rays and, for rays that descend from a camera pixel, that pixel (y * width + x), so a
/// per-ray result can be drawn as an image; pixel is empty for rays with no pixel.
struct RaySet {
  std::vector<Ray> rays;
  std::vector<uint32_t> pixel;
  int width = 0, height = 0;
};

/// Edge of the tiles primary_rays orders its rays by, as the renderer's (render.cpp).
inline constexpr int kPrimaryTile = 16;

/// The top-left pixel (within its tile) of 4x2-pixel block b of a 16x16 tile, b in [0, 32):
/// blocks in Morton (Z) order over the 4 x 8 grid of blocks, so that any aligned run of
/// 2^k blocks covers a compact patch of the tile (what large-packet traversal ranges over).
struct TileBlock {
  int x, y;
};
constexpr TileBlock tile_block(int b) {
  // Bits of b: x0 y0 x1 y1 y2 (from the lowest); the grid is 4 blocks wide, 8 high.
  const int bx = (b & 1) | (b >> 1 & 2), by = (b >> 1 & 1) | (b >> 2 & 6);
  return {4 * bx, 2 * by};
}

/// Pinhole rays through the pixel centres of a width x height image of `scene` (its camera,
/// or one framing its bounds), as the renderer orders them: 16x16-pixel tiles in row order,
/// each in 4x2-pixel blocks in row order, so every 8 consecutive rays form a packet and every
/// 256 a tile. Pixels past the right or bottom edge of a partial block are left out, so only
/// images whose sides are multiples of 4 and 2 give whole packets throughout. Throws rp::Error
/// for a size beyond check_image_size (render/camera.h).
RaySet primary_rays(const Scene& scene, int width, int height);

/// From each hit of `primary` (hits[i] for primary.rays[i]): a shadow ray to the first point
/// light (or, without one, towards a point above the scene's bounds), origin moved off the
/// surface by offset_ray_origin, tfar just short of the light.
RaySet shadow_rays(const Scene& scene, const RaySet& primary, std::span<const Hit> hits);

/// From each hit of `primary`: one cosine-distributed bounce about the face-forwarded
/// geometric normal, from a seeded stream (the same seed gives the same rays).
RaySet diffuse_rays(const Scene& scene, const RaySet& primary, std::span<const Hit> hits, uint64_t seed);

/// The most rays random_rays makes in one call (as `raypack diff --count` takes): 2^28.
inline constexpr size_t kMaxRandomRays = size_t(1) << 28;

/// `count` rays from random points on the sphere around the scene's bounds (radius twice the
/// bounding sphere's) towards random points inside the bounds, seeded. Throws rp::Error for a
/// count beyond kMaxRandomRays.
RaySet random_rays(const Scene& scene, size_t count, uint64_t seed);

}  // namespace rp
