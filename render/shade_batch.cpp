// The scalar shading of a batch (shade_group.h), the sky, the material rows of ShadeScene,
// and the choice between the scalar and the 8-wide implementation.

#include <limits>

#include "core/surface_lanes.h"
#include "render/shade_group.h"
#include "render/shading.h"

namespace rp {

Vec3f sky(const Vec3f& dir) {
  const float t = 0.5f * (normalize(dir).y + 1.0f);
  return Vec3f{0.85f, 0.88f, 0.92f} * (1.0f - t) + Vec3f{0.35f, 0.55f, 0.85f} * t;
}

ShadeScene::ShadeScene(const Scene& s) : scene(s) {
  for (const Material& m : s.materials()) {
    const float terms[kRows] = {m.diffuse.x,  m.diffuse.y,  m.diffuse.z,  m.specular.x, m.specular.y,
                                m.specular.z, m.emission.x, m.emission.y, m.emission.z, m.shininess,
                                m.mirror,     m.opacity};
    for (int r = 0; r < kRows; ++r) rows[r].push_back(terms[r]);
    bounces.push_back(may_bounce(m));
    any_bounce = any_bounce || bounces.back();
  }
  const auto add_shape = [&](const Vec3f& a, float b, uint32_t material) {
    const float terms[kShapeRows] = {a.x, a.y, a.z, b};
    for (int r = 0; r < kShapeRows; ++r) shape_rows[r].push_back(terms[r]);
    shape_material.push_back(int32_t(material));
  };
  for (const Sphere& sp : s.spheres()) add_shape(sp.center, sp.radius, sp.material);
  for (const QuadricShape& q : s.quadrics()) add_shape(Vec3f{0.0f}, 0.0f, q.material);
  for (const PolygonShape& pg : s.polygons()) add_shape(pg.plane.n, pg.plane.d, pg.material);
  for (const Plane& pl : s.planes()) add_shape(pl.normal, pl.d, pl.material);
  shadow_tfar.assign(s.point_lights().size(), kShadowTfar);
  shadow_tfar.resize(s.point_lights().size() + s.directional_lights().size(), std::numeric_limits<float>::infinity());
}

void shade_ray(const ShadeScene& s, const Ray& ray, const Hit& hit, const PathState& ps, uint32_t index, bool bounce,
               ShadeOut& out) {
  const Scene& scene = s.scene;
  if (ps.slot == kInvalidId) return;
  if (!hit.hit()) {
    out.colour[ps.slot] += mul(ps.weight, sky(ray.dir));
    return;
  }
  {
    const SurfacePoint sp = scene.surface(ray, hit);
    const Material& m = scene.materials()[sp.material];
    const MaterialLanes<float> ml{m.diffuse, m.specular, m.emission, m.shininess, m.mirror, m.opacity};
    const ShadedHit<float> h =
        shade_hit<float>(ray.dir, {sp.position, sp.geometric_normal, sp.shading_normal}, ml, ps.weight);
    out.colour[ps.slot] += h.emitted;
    size_t l = 0;
    for (const PointLight& pl : scene.point_lights()) {
      Vec3f to;
      const LightTerm<float> t = point_light_term<float>(h, ml, ps.weight, pl, to);
      if (t.lit) {
        out.shadow[l].push({h.origin, 0.0f, to, s.shadow_tfar[l]}, {ps.slot, t.contribution});
      }
      ++l;
    }
    for (const DirectionalLight& dl : scene.directional_lights()) {
      const LightTerm<float> t = directional_light_term<float>(h, ml, ps.weight, dl);
      if (t.lit) {
        out.shadow[l].push({h.origin, 0.0f, -dl.direction, s.shadow_tfar[l]}, {ps.slot, t.contribution});
      }
      ++l;
    }
    if (bounce && s.bounces[sp.material])
      out.bounces.push_back({index, sp.position, h.ng, h.d, h.origin, h.back, sp.material});
  }
}

void shade_batch_scalar(const ShadeScene& s, std::span<const Ray> rays, std::span<const Hit> hits,
                        std::span<const PathState> paths, bool bounce, ShadeOut& out) {
  for (size_t i = 0; i < rays.size(); ++i) shade_ray(s, rays[i], hits[i], paths[i], uint32_t(i), bounce, out);
}

ShadeBatchFn shade_batch_function() {
  static const bool avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return avx2 ? shade_batch8 : shade_batch_scalar;
}

}  // namespace rp
