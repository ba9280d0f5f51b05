#pragma once
/// Shading a batch of hits, the renderer's per-hit work between its traces: for each ray of
/// the batch, in batch order, the sky (a miss) or the emitted and ambient terms (a hit) added
/// to its path's colour, one shadow ray and waiting contribution per light that lights the
/// hit, and the hits whose material may reflect or refract (the renderer bounces those,
/// render.cpp). Two implementations write the same bits in the same order: shade_batch_scalar,
/// a ray at a time through Scene::surface and shading.h with one lane, and shade_batch8
/// (shade8.cpp, AVX2+FMA), eight rays at a time: their triangles' surface points and all of
/// shading.h on eight lanes, the rays, hits, paths, corners and materials read as vectors.

#include <cstdint>
#include <span>
#include <vector>

#include "base/math.h"
#include "core/ray.h"
#include "core/scene.h"

namespace rp {

/// The weight a path carries and the output slot it adds to (kInvalidId: no contribution).
struct PathState {
  uint32_t slot;
  Vec3f weight;
};

/// A lit contribution waiting for its shadow ray.
struct Pending {
  uint32_t slot;
  Vec3f contribution;
};

/// A hit whose material may reflect or refract, as the bounce needs it.
struct BounceHit {
  uint32_t ray;      ///< its index in the batch
  Vec3f position;    ///< the surface point
  Vec3f ng;          ///< face-forwarded geometric normal
  Vec3f d;           ///< unit ray direction
  Vec3f origin;      ///< where the reflected ray starts
  bool back;         ///< the ray met the back face
  uint32_t material;
};

/// What the shading of a scene reads of it, laid out once per render: the materials' terms
/// as rows (one float per material each), for the 8-wide code to gather.
struct ShadeScene {
  explicit ShadeScene(const Scene& s);
  const Scene& scene;
  enum Row { kd_x, kd_y, kd_z, ks_x, ks_y, ks_z, ke_x, ke_y, ke_z, shininess, mirror, opacity, kRows };
  std::vector<float> rows[kRows];
  /// Shadow ray tfar per light (point lights first, then directional ones).
  std::vector<float> shadow_tfar;
  /// may_bounce of each material, and of any.
  std::vector<uint8_t> bounces;
  bool any_bounce = false;
  /// The analytic primitives' terms as rows, by prim id - Scene::sphere_base() (spheres,
  /// quadrics, polygons, planes): a sphere's centre and radius, a plane's or a polygon's
  /// normal and d (a quadric's: 0), for the 8-wide code to gather; and each one's material.
  enum ShapeRow { shape_ax, shape_ay, shape_az, shape_b, kShapeRows };
  std::vector<float> shape_rows[kShapeRows];
  std::vector<int32_t> shape_material;
};

/// One light's shadow rays from a batch and the contributions waiting for them, in batch
/// order. The records are written in place: the arrays keep the size of the largest batch
/// so far and `count` says how many are this batch's, so appending one initialises nothing
/// it then overwrites.
struct ShadowQueue {
  std::vector<Ray> rays;
  std::vector<Pending> pending;
  size_t count = 0;
  /// Empties the queue for a batch of n rays (each gives at most one shadow ray per light).
  void reset(size_t n) {
    if (rays.size() < n) {
      rays.resize(n);
      pending.resize(n);
    }
    count = 0;
  }
  void push(const Ray& r, const Pending& p) {
    rays[count] = r;
    pending[count++] = p;
  }
  std::span<const Ray> batch_rays() const { return {rays.data(), count}; }
  std::span<const Pending> batch_pending() const { return {pending.data(), count}; }
};

/// Where the shading of one batch goes.
struct ShadeOut {
  std::span<Vec3f> colour;          ///< by path slot
  std::span<ShadowQueue> shadow;    ///< per light, reset for the batch: appended to
  std::vector<BounceHit>& bounces;  ///< appended in batch order (only when `bounce`)
};

/// Shades rays[i] with hit hits[i] for path paths[i], for every i in batch order; `bounce`:
/// also list the hits that may bounce.
using ShadeBatchFn = void (*)(const ShadeScene& s, std::span<const Ray> rays, std::span<const Hit> hits,
                              std::span<const PathState> paths, bool bounce, ShadeOut& out);

/// One ray of a batch (its index `index`), as shade_batch_scalar shades each.
void shade_ray(const ShadeScene& s, const Ray& ray, const Hit& hit, const PathState& ps, uint32_t index, bool bounce,
               ShadeOut& out);

void shade_batch_scalar(const ShadeScene& s, std::span<const Ray> rays, std::span<const Hit> hits,
                        std::span<const PathState> paths, bool bounce, ShadeOut& out);

/// The 8-wide implementation (shade8.cpp, built for AVX2+FMA): only where the CPU has both.
void shade_batch8(const ShadeScene& s, std::span<const Ray> rays, std::span<const Hit> hits,
                  std::span<const PathState> paths, bool bounce, ShadeOut& out);

/// shade_batch8 where this CPU has AVX2 and FMA, else shade_batch_scalar.
ShadeBatchFn shade_batch_function();

/// The sky a missed ray sees (a gradient over the direction's height).
Vec3f sky(const Vec3f& dir);

/// Whether a hit on material m may reflect or refract: the bounce gives a ray exactly when
/// its weight is not zero, which needs a mirror term or transparency.
inline bool may_bounce(const Material& m) { return max_component(m.specular * m.mirror) > 0.0f || 1.0f - m.opacity > 0.0f; }

}  // namespace rp
