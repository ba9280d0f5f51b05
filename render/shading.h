#pragma once
/// The renderer's shading of a hit, in lanes (base/lanes.h): one lane for the scalar
/// renderer, eight for the 8-wide one (render/shade8.cpp), the same operations in the
/// same order, so both give every hit the same bits. Blinn-Phong for point and directional
/// lights (the shadow ray and the contribution waiting for it), the ambient and emitted
/// terms; the mirror and glass bounces, which few hits need, are scalar (render.cpp).

#include <limits>

#include "base/lanes.h"
#include "base/math.h"
#include "core/scene.h"
#include "core/surface_lanes.h"

namespace rp {

/// A material's terms in lanes.
template <class F>
struct MaterialLanes {
  Vec3<F> diffuse, specular, emission;
  F shininess, mirror, opacity;
};

/// A hit as the light terms and bounces see it.
template <class F>
struct ShadedHit {
  typename Lanes<F>::Mask back;  ///< the ray met the back face
  Vec3<F> ng, ns;                ///< face-forwarded to the viewer; ns on ng's side
  Vec3<F> d;                     ///< unit ray direction
  Vec3<F> origin;                ///< where shadow and reflection rays start (offset along ng)
  Vec3<F> emitted;               ///< weight * (emission + ambient): added to the path at once
  F diffuse_weight;              ///< (1 - mirror) * opacity
};

/// The hit `p` of a ray along `dir` carrying `weight`, on material `m`: normals face-forwarded
/// to the viewer, secondary rays offset off the surface by rp::offset_ray_origin (Wächter and
/// Binder 2019), and the unlit terms.
template <class F>
[[gnu::always_inline]] inline ShadedHit<F> shade_hit(const Vec3<F>& dir, const PointLanes<F>& p, const MaterialLanes<F>& m, const Vec3<F>& weight) {
  ShadedHit<F> h;
  h.back = dot(p.geometric_normal, dir) > F(0.0f);
  h.ng = select<F>(h.back, -p.geometric_normal, p.geometric_normal);
  const Vec3<F> ns = select<F>(h.back, -p.shading_normal, p.shading_normal);
  h.ns = select<F>(dot(ns, h.ng) < F(0.0f), h.ng, ns);
  h.d = unit(dir);
  h.origin = Lanes<F>::offset(p.position, h.ng);
  h.diffuse_weight = (F(1.0f) - m.mirror) * m.opacity;
  h.emitted = mul(weight, m.emission + m.diffuse * (F(0.06f) * h.diffuse_weight));
  return h;
}

/// One light's term at a shaded hit: whether it lights the hit (in front of both normals),
/// and the contribution its shadow ray decides on.
template <class F>
struct LightTerm {
  typename Lanes<F>::Mask lit;
  Vec3<F> contribution;
};

/// Blinn-Phong for light arriving along `to_light` (towards the light, any length) with
/// `irradiance`.
template <class F>
[[gnu::always_inline]] inline LightTerm<F> light_term(const ShadedHit<F>& h, const MaterialLanes<F>& m, const Vec3<F>& weight, const Vec3<F>& to_light,
                        const Vec3<F>& irradiance) {
  const Vec3<F> l = unit(to_light);
  const F ndl = dot(h.ns, l);
  // The highlight's power only where the material has a specular colour: without one it adds
  // nothing (0 times any finite power), and most hits of most scenes have none.
  const auto shiny = m.specular.x != F(0.0f) || m.specular.y != F(0.0f) || m.specular.z != F(0.0f);
  F spec(0.0f);
  if (Lanes<F>::any(shiny)) {
    const Vec3<F> half = unit(l + -h.d);
    spec = Lanes<F>::select(shiny, Lanes<F>::pow(max_of(F(0.0f), dot(h.ns, half)), m.shininess), F(0.0f));
  }
  const Vec3<F> c = mul(m.diffuse * (ndl * h.diffuse_weight) + m.specular * spec, irradiance);
  return {!(ndl <= F(0.0f) || dot(h.ng, l) <= F(0.0f)), mul(weight, c)};
}

/// A point light's term: the light's direction and distance from the shadow rays' origin,
/// irradiance intensity / r^2; no light where r = 0.
template <class F>
[[gnu::always_inline]] inline LightTerm<F> point_light_term(const ShadedHit<F>& h, const MaterialLanes<F>& m, const Vec3<F>& weight,
                              const PointLight& light, Vec3<F>& to_light) {
  to_light = Vec3<F>(F(light.position.x), F(light.position.y), F(light.position.z)) - h.origin;
  const F r2 = dot(to_light, to_light);
  const Vec3<F> intensity(F(light.intensity.x), F(light.intensity.y), F(light.intensity.z));
  LightTerm<F> t = light_term(h, m, weight, to_light, intensity / r2);
  t.lit = t.lit && r2 > F(0.0f);
  return t;
}

/// A directional light's term.
template <class F>
[[gnu::always_inline]] inline LightTerm<F> directional_light_term(const ShadedHit<F>& h, const MaterialLanes<F>& m, const Vec3<F>& weight,
                                    const DirectionalLight& light) {
  const Vec3<F> to_light(F(-light.direction.x), F(-light.direction.y), F(-light.direction.z));
  const Vec3<F> irradiance(F(light.irradiance.x), F(light.irradiance.y), F(light.irradiance.z));
  return light_term(h, m, weight, to_light, irradiance);
}

/// Where a point light's shadow ray ends: just short of the light (as a fraction of the ray).
inline constexpr float kShadowTfar = 1.0f - 1e-4f;

}  // namespace rp
