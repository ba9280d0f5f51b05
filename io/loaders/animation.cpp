/// Sampling a scene's node animation and posing the scene (io/loaders/animation.h).

#include "io/loaders/animation.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "base/error.h"

namespace rp {

Affine3d NodeTrs::matrix() const {
  const std::array<double, 4>& r = rotation;
  const double len = std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2] + r[3] * r[3]);
  const double x = r[0] / len, y = r[1] / len, z = r[2] / len, w = r[3] / len;
  const double m[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)},
                          {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)},
                          {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)}};
  Affine3d a;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) a.m[i][j] = m[i][j] * scale[size_t(j)];
    a.m[i][3] = translation[size_t(i)];
  }
  return a;
}

std::optional<CameraDesc> node_camera(const Affine3d& to_world, CameraDesc camera) {
  camera.eye = Vec3f(to_world.point({0, 0, 0}));
  camera.look_at = Vec3f(to_world.point({0, 0, -1}));
  camera.up = Vec3f(to_world.vector({0, 1, 0}));
  const Vec3f view = camera.look_at - camera.eye;
  if (!(camera.vfov_degrees > 0.0f && camera.vfov_degrees < 180.0f) || !in_coordinate_range(camera.eye) ||
      !in_coordinate_range(camera.look_at) || !(length(view) > 0.0f) ||
      !(length(cross(normalize(view), camera.up)) > 1e-6f * length(camera.up)))
    return std::nullopt;
  return camera;
}

PointLight node_point_light(const Affine3d& to_world, const Vec3f& intensity) {
  return PointLight{Vec3f(to_world.point({0, 0, 0})), intensity};
}

DirectionalLight node_directional_light(const Affine3d& to_world, const Vec3f& irradiance) {
  return DirectionalLight{Vec3f(normalize(to_world.vector({0, 0, -1}))), irradiance};
}

namespace {

using Quaternion = std::array<double, 4>;

double dot4(const Quaternion& a, const Quaternion& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]; }

/// `q` divided by its length.
Quaternion normalized(Quaternion q) {
  const double len = std::sqrt(dot4(q, q));
  for (double& c : q) c /= len;
  return q;
}

/// Spherical linear interpolation from unit quaternion `a` to `b` at s in [0, 1], along the
/// shorter arc (b negated when a . b < 0: q and -q are one rotation). The angle between them
/// is 2 atan2(|a - b|, |a + b|) (Kahan, "How futile are mindless assessments of roundoff",
/// section 12), accurate for angles near 0 and pi where acos(a . b) is not, so no switch to a
/// normalised lerp is needed near 0 (Shoemake 1985, "Animating rotation with quaternion
/// curves", for the formula).
Quaternion slerp(const Quaternion& a, Quaternion b, double s) {
  if (dot4(a, b) < 0.0)
    for (double& c : b) c = -c;
  Quaternion diff, sum;
  for (size_t i = 0; i < 4; ++i) {
    diff[i] = a[i] - b[i];
    sum[i] = a[i] + b[i];
  }
  const double theta = 2.0 * std::atan2(std::sqrt(dot4(diff, diff)), std::sqrt(dot4(sum, sum)));
  if (theta == 0.0) return a;
  const double sin_theta = std::sin(theta);
  const double wa = std::sin((1.0 - s) * theta) / sin_theta, wb = std::sin(s * theta) / sin_theta;
  Quaternion q;
  for (size_t i = 0; i < 4; ++i) q[i] = wa * a[i] + wb * b[i];
  return normalized(q);
}

}  // namespace

std::array<double, 4> sample(const AnimationCurve& c, double seconds) {
  const size_t n = c.components();
  const bool cubic = c.interpolation == Interpolation::cubic_spline;
  const size_t per_key = cubic ? 3 * n : n;  // numbers per keyframe
  // Keyframe k's value (the middle of a cubic spline's triple).
  const auto value = [&](size_t k) { return &c.values[k * per_key + (cubic ? n : 0)]; };
  const auto copy = [&](const double* v) {
    std::array<double, 4> out{0, 0, 0, 0};
    std::copy(v, v + n, out.begin());
    return out;
  };
  std::array<double, 4> out;
  if (!(seconds > c.times.front())) {
    out = copy(value(0));
  } else if (seconds >= c.times.back()) {
    out = copy(value(c.times.size() - 1));
  } else {
    // k: the last keyframe at or before `seconds`; k + 1 exists.
    const size_t k = size_t(std::upper_bound(c.times.begin(), c.times.end(), seconds) - c.times.begin()) - 1;
    const double d = c.times[k + 1] - c.times[k], s = (seconds - c.times[k]) / d;
    const double* a = value(k);
    const double* b = value(k + 1);
    out = {0, 0, 0, 0};
    if (c.interpolation == Interpolation::step) {
      out = copy(a);
    } else if (c.interpolation == Interpolation::linear) {
      if (c.property == AnimatedProperty::rotation) return slerp(copy(a), copy(b), s);
      for (size_t i = 0; i < n; ++i) out[i] = a[i] + s * (b[i] - a[i]);
    } else {
      // Hermite basis (glTF 2.0 Appendix C); the out-tangent of k follows its value, the
      // in-tangent of k + 1 precedes its value.
      const double s2 = s * s, s3 = s2 * s;
      const double h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s, h01 = -2 * s3 + 3 * s2, h11 = s3 - s2;
      const double* out_tangent = a + n;
      const double* in_tangent = b - n;
      for (size_t i = 0; i < n; ++i)
        out[i] = h00 * a[i] + h10 * d * out_tangent[i] + h01 * b[i] + h11 * d * in_tangent[i];
    }
  }
  if (c.property == AnimatedProperty::rotation) out = normalized(out);
  return out;
}

SceneAnimation::SceneAnimation(std::string file, std::vector<AnimationCurve> curves, std::vector<AnimatedNode> nodes,
                               std::vector<AnimatedTarget> targets, AnimationCounts counts)
    : file_(std::move(file)),
      curves_(std::move(curves)),
      nodes_(std::move(nodes)),
      targets_(std::move(targets)),
      counts_(counts) {
  for (const AnimationCurve& c : curves_) {
    RP_CHECK(!c.times.empty() && c.values.size() == c.times.size() * c.components() *
                                                        (c.interpolation == Interpolation::cubic_spline ? 3 : 1),
             file_, ": an animation curve of ", c.times.size(), " keyframes has ", c.values.size(), " numbers");
    duration_ = std::max(duration_, c.times.back());
  }
  for (size_t i = 0; i < nodes_.size(); ++i) {
    RP_CHECK(nodes_[i].parent < int(i), file_, ": ", nodes_[i].path, ": its parent is not listed before it");
    for (int curve : nodes_[i].curves)
      RP_CHECK(curve < int(curves_.size()), file_, ": ", nodes_[i].path, ": no curve ", curve);
  }
  for (const AnimatedTarget& t : targets_) RP_CHECK(t.node < nodes_.size(), file_, ": a target of no animated node");
}

std::vector<Affine3d> SceneAnimation::node_to_world(double seconds) const {
  std::vector<Affine3d> world(nodes_.size());
  for (size_t i = 0; i < nodes_.size(); ++i) {
    const AnimatedNode& node = nodes_[i];
    Affine3d local = node.local;
    if (node.animated()) {
      NodeTrs trs = node.rest;
      if (node.curves[0] >= 0) {
        const std::array<double, 4> v = sample(curves_[size_t(node.curves[0])], seconds);
        trs.translation = {v[0], v[1], v[2]};
      }
      if (node.curves[1] >= 0) trs.rotation = sample(curves_[size_t(node.curves[1])], seconds);
      if (node.curves[2] >= 0) {
        const std::array<double, 4> v = sample(curves_[size_t(node.curves[2])], seconds);
        trs.scale = {v[0], v[1], v[2]};
      }
      local = trs.matrix();
    }
    world[i] = compose(node.parent < 0 ? node.base : world[size_t(node.parent)], local);
  }
  return world;
}

void SceneAnimation::apply(Scene& scene, double seconds) const {
  RP_CHECK(std::isfinite(seconds), file_, ": the time ", seconds, " s is not a finite number");
  if (targets_.empty()) return;
  const std::vector<Affine3d> world = node_to_world(seconds);
  for (const AnimatedTarget& t : targets_) {
    const Affine3d& to_world = world[t.node];
    try {
      switch (t.kind) {
        case AnimatedTarget::Kind::instance: {
          RP_CHECK(t.index < scene.instances().size(), "instance ", t.index, " is not in the scene (",
                   scene.instances().size(), " instances)");
          const Affine3f m(to_world);
          if (!(scene.instances()[t.index].object_to_world == m)) scene.set_transform(t.index, m);
          break;
        }
        case AnimatedTarget::Kind::point_light:
          scene.set_light(t.index, node_point_light(to_world, t.power));
          break;
        case AnimatedTarget::Kind::directional_light:
          scene.set_light(t.index, node_directional_light(to_world, t.power));
          break;
        case AnimatedTarget::Kind::camera: {
          const std::optional<CameraDesc> c = node_camera(to_world, t.camera);
          RP_CHECK(c.has_value(),
                   "its placement makes no camera (no view direction, an up along it, or a point "
                   "outside the coordinate range)");
          scene.set_camera(*c);
          break;
        }
      }
    } catch (const Error& e) {
      throw Error(cat(file_, ": ", nodes_[t.node].path, " at ", seconds, " s: ", e.what()));
    }
  }
}

}  // namespace rp
