#include "analysis/motion.h"

#include <cmath>

namespace rp {

std::vector<Vec3f> wobbled(Strided<Vec3f> positions, const Box3f& box, double amplitude, double phase) {
  const double l = box.empty() ? 0.0 : length(Vec3d(box.hi) - Vec3d(box.lo));
  std::vector<Vec3f> out(positions.begin(), positions.end());
  if (!(l > 0.0)) return out;
  const double a = amplitude * l, w = 2.0 * kPi * 3.0 / l, s = 2.0 * kPi * phase;
  for (Vec3f& p : out) {
    const Vec3d q(p);
    p = Vec3f(q + a * Vec3d(std::sin(w * q.y + s), std::sin(w * q.z + s), std::sin(w * q.x + s)));
  }
  return out;
}

void wobble_meshes(Scene& scene, const Scene& rest, double amplitude, double phase) {
  for (uint32_t m = 0; m < scene.meshes().size(); ++m)
    scene.set_vertices(m, wobbled(rest.meshes()[m].positions, rest.mesh_bounds(m), amplitude, phase));
}

void jostle_instances(Scene& scene, const Scene& rest, double amplitude, double phase) {
  for (uint32_t i = 0; i < scene.instances().size(); ++i) {
    const Instance& in = rest.instances()[i];
    const double l = in.bounds.empty() ? 0.0 : length(Vec3d(in.bounds.hi) - Vec3d(in.bounds.lo));
    const double u = 2.0 * kPi * (phase + 0.618034 * double(i)), v = 2.0 * kPi * (0.5 * phase + 0.414214 * double(i));
    const Vec3d dir(std::cos(u) * std::sin(v), std::sin(u) * std::sin(v), std::cos(v));
    // A turn about `dir` through the box's centre, then the move along it.
    const double angle = 2.0 * kPi * 3.0 * amplitude, c = std::cos(angle), s = std::sin(angle), t = 1.0 - c;
    const double r[3][3] = {{c + t * dir.x * dir.x, t * dir.x * dir.y - s * dir.z, t * dir.x * dir.z + s * dir.y},
                            {t * dir.x * dir.y + s * dir.z, c + t * dir.y * dir.y, t * dir.y * dir.z - s * dir.x},
                            {t * dir.x * dir.z - s * dir.y, t * dir.y * dir.z + s * dir.x, c + t * dir.z * dir.z}};
    const Vec3d centre = in.bounds.empty() ? Vec3d(0.0) : 0.5 * (Vec3d(in.bounds.lo) + Vec3d(in.bounds.hi));
    const Affine3d m(in.object_to_world);
    Affine3f out;
    for (int row = 0; row < 3; ++row) {
      double shift = centre[row] + amplitude * l * dir[row];
      for (int col = 0; col < 3; ++col) {
        double lin = 0.0;
        for (int k = 0; k < 3; ++k) lin += r[row][k] * m.m[k][col];
        out.m[row][col] = float(lin);
        shift -= r[row][col] * centre[col];
      }
      double tr = shift;
      for (int k = 0; k < 3; ++k) tr += r[row][k] * m.m[k][3];
      out.m[row][3] = float(tr);
    }
    scene.set_transform(i, out);
  }
}

}  // namespace rp
