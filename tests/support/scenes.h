#pragma once
// Seeded scenes and rays the backend tests share: a triangle soup, a closed tessellated sphere
// (shared edges and vertices everywhere), every analytic kind, and ray sets around them.

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "base/math.h"
#include "core/affine.h"
#include "core/geometry/quadric.h"
#include "core/ray.h"
#include "core/scene.h"

namespace rp::test {

inline Vec3f random_in_box(std::mt19937& rng, float lo, float hi) {
  std::uniform_real_distribution<float> u(lo, hi);
  return {u(rng), u(rng), u(rng)};
}

inline Vec3f random_direction(std::mt19937& rng) {
  std::normal_distribution<float> n(0.0f, 1.0f);
  Vec3f d;
  do d = {n(rng), n(rng), n(rng)};
  while (length(d) < 1e-3f);
  return normalize(d);
}

inline Scene triangle_soup(uint32_t seed, int count) {
  std::mt19937 rng(seed);
  TriangleMesh m;
  m.name = "soup";
  for (int i = 0; i < count; ++i) {
    const Vec3f c = random_in_box(rng, -1.0f, 1.0f);
    for (int k = 0; k < 3; ++k) {
      m.positions.push_back(c + random_in_box(rng, -0.15f, 0.15f));
      m.indices.push_back(uint32_t(m.positions.size() - 1));
    }
  }
  Scene s;
  s.add_mesh(std::move(m));
  return s;
}

/// Closed UV sphere of radius 1: shared edges and vertices everywhere.
inline Scene tessellated_sphere(int slices, int stacks) {
  TriangleMesh m;
  m.name = "uv_sphere";
  for (int j = 0; j <= stacks; ++j)
    for (int i = 0; i < slices; ++i) {
      const double th = kPi * j / stacks, ph = 2 * kPi * i / slices;
      m.positions.push_back({float(std::sin(th) * std::cos(ph)), float(std::cos(th)), float(std::sin(th) * std::sin(ph))});
    }
  for (int j = 0; j < stacks; ++j)
    for (int i = 0; i < slices; ++i) {
      const uint32_t a = j * slices + i, b = j * slices + (i + 1) % slices;
      const uint32_t c = (j + 1) * slices + (i + 1) % slices, d = (j + 1) * slices + i;
      if (j != 0) m.indices.insert(m.indices.end(), {a, b, c});
      if (j != stacks - 1) m.indices.insert(m.indices.end(), {a, c, d});
    }
  Scene s;
  s.add_mesh(std::move(m));
  return s;
}

inline Scene analytic_scene() {
  Scene s;
  using Qf = Quadric<float>;
  s.add_sphere({{0.0f, 0.0f, 0.0f}, 0.6f, 0});
  s.add_sphere({{1.2f, 0.3f, -0.4f}, 0.25f, 0});
  s.add_quadric({Qf::ellipsoid({-1.0f, 0.5f, 0.5f}, {0.5f, 0.3f, 0.4f}), 0});
  s.add_quadric({Qf::cylinder({1.0f, -0.8f, 0.8f}, 0.3f, 0.2f, 0.5f, 1), 0});
  s.add_quadric({Qf::cone({-1.0f, -1.0f, -0.6f}, 0.4f, 0.4f, 0.6f, 1), 0});
  s.add_quadric({Qf::hyperboloid_one_sheet({0.6f, 1.1f, 0.9f}, 0.2f, 0.2f, 0.3f, 0.4f, 0), 0});
  s.add_quadric({Qf::hyperboloid_two_sheets({-0.3f, -1.2f, 1.2f}, 0.2f, 0.2f, 0.2f, 0.5f, 2), 0});
  s.add_quadric({Qf::paraboloid({0.2f, 1.0f, -1.2f}, 0.3f, 0.3f, 0.5f, 1), 0});
  const std::vector<Vec3f> quad{{-1.5f, -1.5f, -1.5f}, {-0.5f, -1.5f, -1.5f}, {-0.5f, -0.5f, -1.5f}, {-1.5f, -0.5f, -1.5f}};
  s.add_polygon(quad, 0);
  std::vector<Vec3f> star;
  for (int k = 0; k < 10; ++k) {
    const float a = float(kPi) * (0.5f + float(k) / 5.0f), r = (k % 2 == 0) ? 0.7f : 0.3f;
    star.push_back({1.0f + r * std::cos(a), 0.0f, 1.2f + r * std::sin(a)});  // in the plane y = 0... tilted below
  }
  for (Vec3f& v : star) v.y = 0.3f * (v.x - 1.0f) - 0.5f;
  s.add_polygon(star, 0);
  s.add_plane({normalize(Vec3f{0.1f, 1.0f, 0.05f}), 1.8f, 0});
  return s;
}

/// Rays aimed from a sphere of radius 4 at random points in [-1.5, 1.5]^3, a quarter with a
/// finite tfar cutting the segment short, in groups of 8 with nearby targets (coherent-ish).
inline std::vector<Ray> random_rays(uint32_t seed, int count) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  std::vector<Ray> rays;
  for (int g = 0; g < count / 8; ++g) {
    const Vec3f org = random_direction(rng) * 4.0f;
    const Vec3f target = random_in_box(rng, -1.5f, 1.5f);
    for (int i = 0; i < 8; ++i) {
      Ray r{org, 0.0f, (target + random_in_box(rng, -0.2f, 0.2f)) - org, std::numeric_limits<float>::infinity()};
      if (u01(rng) < 0.25f) r.tfar = 0.3f + u01(rng);
      if (u01(rng) < 0.1f) r.tnear = 0.5f * u01(rng);
      rays.push_back(r);
    }
  }
  return rays;
}

/// Axis-parallel rays with +0 and -0 in the other components, on a grid of origins that
/// includes coordinates exactly on primitive bounds (multiples of 0.25).
inline std::vector<Ray> axis_rays() {
  std::vector<Ray> rays;
  for (int axis = 0; axis < 3; ++axis)
    for (float sign : {-1.0f, 1.0f})
      for (int a = -6; a <= 6; ++a)
        for (int b = -6; b <= 6; ++b) {
          Ray r;
          r.org[axis] = -4.0f * sign;
          r.org[(axis + 1) % 3] = 0.25f * float(a);
          r.org[(axis + 2) % 3] = 0.25f * float(b);
          r.dir = Vec3f{(a + b) % 2 ? 0.0f : -0.0f};
          r.dir[axis] = sign;
          rays.push_back(r);
        }
  return rays;
}

/// A triangle soup in [-1.1, 1.1]^3 (every 50th triangle followed by a zero-area one when
/// `with_degenerate`), a sphere, a clipped cylinder and a triangular polygon: every primitive
/// kind a BVH holds.
inline Scene mixed_soup(uint32_t seed, int count, bool with_degenerate) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), s(-0.1f, 0.1f);
  TriangleMesh m;
  m.name = "soup";
  for (int i = 0; i < count; ++i) {
    const Vec3f c{u(rng), u(rng), u(rng)};
    for (int k = 0; k < 3; ++k) m.positions.push_back(c + Vec3f{s(rng), s(rng), s(rng)});
    const uint32_t b = uint32_t(m.positions.size() - 3);
    m.indices.insert(m.indices.end(), {b, b + 1, b + 2});
    if (with_degenerate && i % 50 == 0) m.indices.insert(m.indices.end(), {b, b, b + 1});  // zero area
  }
  Scene sc;
  sc.add_mesh(std::move(m));
  sc.add_sphere({{0.5f, 0.5f, 0.5f}, 0.2f, 0});
  sc.add_quadric({Quadric<float>::cylinder({-0.5f, 0.0f, 0.3f}, 0.2f, 0.2f, 0.4f, 1), 0});
  const std::vector<Vec3f> tri{{0, 0, 1.5f}, {1, 0, 1.5f}, {0, 1, 1.5f}};
  sc.add_polygon(tri, 0);
  return sc;
}

/// Long thin triangles across [-1, 1]^3, as Sponza's floor strips and columns are: each runs
/// from near one random point to near another, so its box is large and mostly empty, and
/// object splits leave the children overlapping (where spatial splits pay). A sphere in the
/// middle, so the tree also holds an analytic primitive.
inline Scene sliver_soup(uint32_t seed, int count) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> w(-0.02f, 0.02f);
  TriangleMesh m;
  m.name = "slivers";
  for (int i = 0; i < count; ++i) {
    const Vec3f a = random_in_box(rng, -1.0f, 1.0f), b = random_in_box(rng, -1.0f, 1.0f);
    const uint32_t base = uint32_t(m.positions.size());
    m.positions.insert(m.positions.end(), {a, b, b + Vec3f{w(rng), w(rng), w(rng)}});
    m.indices.insert(m.indices.end(), {base, base + 1, base + 2});
  }
  Scene sc;
  sc.add_mesh(std::move(m));
  sc.add_sphere({{0.1f, -0.2f, 0.3f}, 0.15f, 0});
  return sc;
}

/// An affine map: scale (per axis), then rotate by `degrees` about unit `axis`, then translate.
inline Affine3f placement(const Vec3f& scale, const Vec3f& axis, float degrees, const Vec3f& translate) {
  const double a = double(degrees) * kPi / 180.0, c = std::cos(a), s = std::sin(a), t = 1.0 - c;
  const Vec3d k = normalize(Vec3d(axis));
  const double r[3][3] = {{c + t * k.x * k.x, t * k.x * k.y - s * k.z, t * k.x * k.z + s * k.y},
                          {t * k.x * k.y + s * k.z, c + t * k.y * k.y, t * k.y * k.z - s * k.x},
                          {t * k.x * k.z - s * k.y, t * k.y * k.z + s * k.x, c + t * k.z * k.z}};
  Affine3f m;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) m.m[i][j] = float(r[i][j] * double(scale[j]));
    m.m[i][3] = translate[i];
  }
  return m;
}

/// A closed tessellated sphere (a mesh of shared edges and vertices) and a triangle soup, each
/// stored once and placed several times in [-1.5, 1.5]^3 (rotated, scaled unevenly, one
/// mirrored), beside a world mesh, a sphere, a quadric and a plane: every kind of primitive
/// next to the instances.
inline Scene instanced_scene() {
  const Scene ball = tessellated_sphere(24, 12), soup = triangle_soup(21, 300);
  Scene s;
  const uint32_t b = s.add_instanced_mesh(to_triangle_mesh(ball.meshes()[0]));
  const uint32_t q = s.add_instanced_mesh(to_triangle_mesh(soup.meshes()[0]));
  s.add_instance(b, placement({0.4f, 0.4f, 0.4f}, {0, 1, 0}, 0.0f, {-0.8f, 0.6f, 0.2f}));
  s.add_instance(b, placement({0.5f, 0.25f, 0.35f}, {1, 1, 0}, 35.0f, {0.7f, 0.5f, -0.6f}));
  s.add_instance(b, placement({-0.3f, 0.3f, 0.3f}, {0, 0, 1}, 70.0f, {0.1f, -0.7f, 0.8f}));  // mirrored
  s.add_instance(q, placement({0.5f, 0.5f, 0.5f}, {0, 1, 0}, 90.0f, {-0.6f, -0.5f, -0.7f}));
  s.add_instance(q, placement({0.4f, 0.7f, 0.4f}, {1, 0, 1}, -40.0f, {0.8f, -0.2f, 0.9f}));
  TriangleMesh floor;
  floor.name = "floor";
  floor.positions = {{-1.4f, -1.2f, -1.4f}, {1.4f, -1.2f, -1.4f}, {1.4f, -1.2f, 1.4f}, {-1.4f, -1.2f, 1.4f}};
  floor.indices = {0, 1, 2, 0, 2, 3};
  s.add_mesh(floor);
  s.add_sphere({{0.0f, 0.1f, 0.0f}, 0.3f, 0});
  s.add_quadric({Quadric<float>::cylinder({-0.9f, -0.6f, 0.9f}, 0.2f, 0.2f, 0.4f, 1), 0});
  s.add_plane({{0.0f, 0.0f, 1.0f}, 1.45f, 0});
  return s;
}

/// instanced_scene with a tilted pentagon beside the rest: every primitive kind next to the
/// instances.
inline Scene instanced_scene_with_polygon() {
  Scene s = instanced_scene();
  std::vector<Vec3f> pentagon;
  for (int k = 0; k < 5; ++k) {
    const float a = 2.0f * float(kPi) * float(k) / 5.0f;
    pentagon.push_back({-0.9f + 0.4f * std::cos(a), 1.0f + 0.2f * std::cos(a), 0.9f + 0.4f * std::sin(a)});
  }
  s.add_polygon(pentagon, 0);
  return s;
}

/// `s` without its quadrics (what closest points refuse).
inline Scene without_quadrics(Scene s) {
  while (!s.quadrics().empty()) s.remove_quadric(uint32_t(s.quadrics().size() - 1));
  return s;
}

/// `scene` with every instance baked into a world mesh (its mesh's positions mapped by the
/// instance's transform in double, normals dropped), instanced meshes left out: the same
/// triangles, flat, with the same materials, lights and camera. Prim ids differ (the baked
/// copies come after the world meshes).
inline Scene flattened(const Scene& scene) {
  Scene out;
  for (size_t i = 1; i < scene.materials().size(); ++i) out.add_material(scene.materials()[i]);
  for (const PointLight& l : scene.point_lights()) out.add_light(l);
  for (const DirectionalLight& l : scene.directional_lights()) out.add_light(l);
  if (scene.camera()) out.set_camera(*scene.camera());
  for (size_t i = 0; i < scene.meshes().size(); ++i)
    if (!scene.is_instanced(i)) out.add_mesh(to_triangle_mesh(scene.meshes()[i]));
  for (const Instance& in : scene.instances()) {
    TriangleMesh m = to_triangle_mesh(scene.meshes()[in.mesh]);
    const Affine3d t(in.object_to_world);
    for (Vec3f& p : m.positions) p = Vec3f(t.point(Vec3d(p)));
    m.normals.clear();
    out.add_mesh(std::move(m));
  }
  for (const Sphere& sp : scene.spheres()) out.add_sphere(sp);
  for (const QuadricShape& qs : scene.quadrics()) out.add_quadric(qs);
  for (const Plane& p : scene.planes()) out.add_plane(p);
  return out;
}

}  // namespace rp::test
