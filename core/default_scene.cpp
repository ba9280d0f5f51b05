#include <cmath>

#include "core/scene.h"

namespace rp {

namespace {

/// Point on a (p, q) torus knot of major radius R at parameter u in [0, 2pi)
/// (the curve three.js' TorusKnotGeometry uses).
Vec3f torus_knot_point(float u, int p, int q, float radius) {
  const float qu = float(q) * u / float(p);
  const float cs = std::cos(qu);
  return {radius * (2.0f + cs) * 0.5f * std::cos(u), radius * (2.0f + cs) * 0.5f * std::sin(u),
          radius * std::sin(qu) * 0.5f};
}

/// Closed tube around a (2, 3) torus knot: tubular x radial quads, two triangles each,
/// vertex normals from the tube's centre line.
TriangleMesh torus_knot(Vec3f centre, float radius, float tube, int tubular, int radial, uint32_t material) {
  const int p = 2, q = 3;
  TriangleMesh m;
  m.name = "torus_knot";
  m.material = material;
  m.positions.reserve(size_t(tubular) * radial);
  m.normals.reserve(size_t(tubular) * radial);
  for (int i = 0; i < tubular; ++i) {
    const float u = float(i) / float(tubular) * float(p) * 2.0f * float(kPi);
    const Vec3f p1 = torus_knot_point(u, p, q, radius);
    const Vec3f p2 = torus_knot_point(u + 0.01f, p, q, radius);
    const Vec3f t = p2 - p1;
    Vec3f n = p2 + p1;
    const Vec3f b = normalize(cross(t, n));
    n = normalize(cross(b, t));
    for (int j = 0; j < radial; ++j) {
      const float v = float(j) / float(radial) * 2.0f * float(kPi);
      const Vec3f dir = n * (-std::cos(v)) + b * std::sin(v);
      m.positions.push_back(centre + p1 + dir * tube);
      m.normals.push_back(dir);
    }
  }
  m.indices.reserve(size_t(tubular) * radial * 6);
  for (int i = 0; i < tubular; ++i)
    for (int j = 0; j < radial; ++j) {
      const uint32_t a = uint32_t(i * radial + j);
      const uint32_t b = uint32_t(((i + 1) % tubular) * radial + j);
      const uint32_t c = uint32_t(((i + 1) % tubular) * radial + (j + 1) % radial);
      const uint32_t d = uint32_t(i * radial + (j + 1) % radial);
      m.indices.insert(m.indices.end(), {a, b, d, b, c, d});
    }
  return m;
}

}  // namespace

Scene make_default_scene() {
  Scene s;
  const uint32_t ground = s.add_material({.name = "ground", .diffuse = {0.55f, 0.55f, 0.52f}});
  const uint32_t gold = s.add_material({.name = "knot",
                                        .diffuse = {0.80f, 0.50f, 0.16f},
                                        .specular = {0.6f, 0.5f, 0.3f},
                                        .shininess = 60.0f});
  const uint32_t mirror = s.add_material({.name = "mirror",
                                          .diffuse = {0.05f, 0.05f, 0.05f},
                                          .specular = {0.9f, 0.9f, 0.9f},
                                          .shininess = 200.0f,
                                          .mirror = 0.85f});
  const uint32_t red = s.add_material(
      {.name = "red", .diffuse = {0.75f, 0.12f, 0.10f}, .specular = {0.4f, 0.4f, 0.4f}, .shininess = 40.0f});
  const uint32_t blue = s.add_material(
      {.name = "blue", .diffuse = {0.15f, 0.30f, 0.80f}, .specular = {0.3f, 0.3f, 0.3f}, .shininess = 30.0f});
  const uint32_t green = s.add_material({.name = "green", .diffuse = {0.20f, 0.65f, 0.25f}});
  const uint32_t white = s.add_material({.name = "white", .diffuse = {0.85f, 0.85f, 0.85f}});
  const uint32_t purple = s.add_material(
      {.name = "purple", .diffuse = {0.55f, 0.25f, 0.70f}, .specular = {0.3f, 0.3f, 0.3f}, .shininess = 25.0f});

  // 512 x 64 quads = 65,536 triangles, closed (genus 1) and with vertex normals.
  s.add_mesh(torus_knot({0.0f, 1.75f, -0.5f}, 1.1f, 0.28f, 512, 64, gold));

  s.add_sphere({{-2.7f, 0.75f, 0.9f}, 0.75f, mirror});
  const uint32_t glass = s.add_material({.name = "glass",
                                         .diffuse = {0.0f, 0.0f, 0.0f},
                                         .specular = {1.0f, 1.0f, 1.0f},
                                         .shininess = 300.0f,
                                         .ior = 1.5f,
                                         .opacity = 0.0f});
  s.add_sphere({{1.2f, 0.45f, 2.0f}, 0.45f, glass});

  using Qf = Quadric<float>;
  s.add_quadric({Qf::cylinder({2.9f, 0.7f, -0.6f}, 0.4f, 0.4f, 0.7f, 1), blue});
  s.add_quadric({Qf::ellipsoid({2.6f, 0.45f, 1.5f}, {0.6f, 0.45f, 0.4f}), purple});
  s.add_quadric({Qf::cone({-1.0f, 0.0f, 2.4f}, 0.35f, 0.35f, 0.9f, 1), green});
  s.add_quadric({Qf::hyperboloid_one_sheet({-3.1f, 1.0f, -1.6f}, 0.3f, 0.3f, 0.6f, 1.0f, 1), red});
  s.add_quadric({Qf::paraboloid({0.1f, 0.0f, 2.6f}, 0.35f, 0.35f, 0.7f, 1), blue});
  s.add_quadric({Qf::hyperboloid_two_sheets({-0.9f, 0.9f, -3.0f}, 0.25f, 0.25f, 0.25f, 0.9f, 1), purple});

  // A five-pointed star standing behind the knot: non-convex, so the even-odd test applies.
  std::vector<Vec3f> star;
  for (int k = 0; k < 10; ++k) {
    const float a = float(kPi) * (0.5f + float(k) / 5.0f);
    const float r = (k % 2 == 0) ? 1.3f : 0.55f;
    star.push_back({2.6f + r * std::cos(a), 2.3f + r * std::sin(a), -3.2f});
  }
  s.add_polygon(star, white);

  s.add_plane({{0.0f, 1.0f, 0.0f}, 0.0f, ground});

  s.add_light(PointLight{{4.0f, 7.0f, 5.0f}, {70.0f, 68.0f, 62.0f}});
  s.add_light(DirectionalLight{normalize(Vec3f{-0.4f, -1.0f, -0.5f}), {0.35f, 0.37f, 0.42f}});
  s.set_camera({{0.0f, 3.4f, 8.5f}, {0.0f, 1.1f, 0.0f}, {0.0f, 1.0f, 0.0f}, 42.0f});
  return s;
}

}  // namespace rp
