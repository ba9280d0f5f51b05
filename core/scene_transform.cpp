#include "core/scene_transform.h"

#include <cmath>
#include <utility>
#include <vector>

#include "base/error.h"

namespace rp {

Scene transformed(const Scene& s, double scale, const Vec3d& off) {
  RP_CHECK(scale > 0.0 && std::isfinite(scale), "transformed: scale ", scale, " must be finite and > 0");
  auto P = [&](const Vec3f& p) { return Vec3f(Vec3d(p) * scale + off); };
  Scene out;
  for (size_t i = 1; i < s.materials().size(); ++i) out.add_material(s.materials()[i]);
  for (size_t i = 0; i < s.meshes().size(); ++i) {
    if (s.is_instanced(i)) {  // stays in its object space; its instances move
      if (s.is_shared(i))
        out.add_shared_instanced_mesh(s.meshes()[i]);
      else
        out.add_instanced_mesh(to_triangle_mesh(s.meshes()[i]));
      continue;
    }
    TriangleMesh m = to_triangle_mesh(s.meshes()[i]);
    for (Vec3f& p : m.positions) p = P(p);
    out.add_mesh(std::move(m));
  }
  for (const Instance& in : s.instances()) {
    Affine3d m(in.object_to_world);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) m.m[r][c] *= scale;
      m.m[r][3] += off[r];
    }
    out.add_instance(in.mesh, Affine3f(m));
  }
  for (Sphere sp : s.spheres()) {
    sp.center = P(sp.center);
    sp.radius = float(double(sp.radius) * scale);
    out.add_sphere(sp);
  }
  for (QuadricShape q : s.quadrics()) {
    Quadricf& f = q.quadric;
    const double s2 = scale * scale;
    f.A = float(f.A / s2); f.B = float(f.B / s2); f.C = float(f.C / s2);
    f.D = float(f.D / s2); f.E = float(f.E / s2); f.F = float(f.F / s2);
    f.G = float(f.G / scale); f.H = float(f.H / scale); f.I = float(f.I / scale);
    f.center = P(f.center);
    f.clip = {P(f.clip.lo), P(f.clip.hi)};
    out.add_quadric(q);
  }
  for (const PolygonShape& pg : s.polygons()) {
    std::vector<Vec3f> v(s.polygon_vertices().begin() + pg.first, s.polygon_vertices().begin() + pg.first + pg.count);
    for (Vec3f& p : v) p = P(p);
    out.add_polygon(v, pg.material);
  }
  for (Plane pl : s.planes()) {
    pl.d = float(double(pl.d) * scale - dot(Vec3d(pl.normal), off));
    out.add_plane(pl);
  }
  for (PointLight l : s.point_lights()) {
    l.position = P(l.position);
    out.add_light(l);
  }
  for (const DirectionalLight& l : s.directional_lights()) out.add_light(l);
  if (s.camera()) {
    CameraDesc c = *s.camera();
    c.eye = P(c.eye);
    c.look_at = P(c.look_at);
    c.aperture = float(c.aperture * scale);
    c.focus_distance = float(c.focus_distance * scale);
    out.set_camera(c);
  }
  return out;
}

}  // namespace rp
