#pragma once
// Animated glTF files for the tests, and the tests' own sampling of glTF animation curves:
// written from the formulas of the glTF 2.0 specification (its "Animations" section and
// Appendix C), independently of the loader's (io/loaders/animation.cpp): lerp as (1 - s) a +
// s b, slerp by the textbook acos formula, the cubic Hermite spline by its four basis
// polynomials. AnimatedGltf::still flattens an animated file into a still one at a time with
// them, the "by hand" copy a posed scene is compared with.

#include <cmath>
#include <string>
#include <vector>

#include "tests/support/gltf_files.h"

namespace rp::test {

/// (1 - s) a + s b, component by component.
inline std::vector<double> lerp(const std::vector<double>& a, const std::vector<double>& b, double s) {
  std::vector<double> out(a.size());
  for (size_t i = 0; i < a.size(); ++i) out[i] = (1.0 - s) * a[i] + s * b[i];
  return out;
}

/// `q` divided by its length.
inline std::vector<double> unit(std::vector<double> q) {
  double len = 0.0;
  for (double c : q) len += c * c;
  len = std::sqrt(len);
  for (double& c : q) c /= len;
  return q;
}

/// Slerp of unit quaternions a to b at s along the shorter arc (b negated when a . b < 0):
/// theta = acos(a . b), (sin((1 - s) theta) a + sin(s theta) b) / sin theta; a when they are
/// the same rotation.
inline std::vector<double> slerp(const std::vector<double>& a, std::vector<double> b, double s) {
  double d = 0.0;
  for (size_t i = 0; i < 4; ++i) d += a[i] * b[i];
  if (d < 0.0) {
    for (double& c : b) c = -c;
    d = -d;
  }
  if (d >= 1.0) return a;
  const double theta = std::acos(d);
  std::vector<double> out(4);
  for (size_t i = 0; i < 4; ++i)
    out[i] = (std::sin((1.0 - s) * theta) * a[i] + std::sin(s * theta) * b[i]) / std::sin(theta);
  return out;
}

/// The cubic Hermite spline from value v0 (out-tangent b0) to v1 (in-tangent a1) over an
/// interval of d seconds, at s in [0, 1]: (2s^3 - 3s^2 + 1) v0 + (s^3 - 2s^2 + s) d b0 +
/// (-2s^3 + 3s^2) v1 + (s^3 - s^2) d a1.
inline std::vector<double> hermite(const std::vector<double>& v0, const std::vector<double>& b0,
                                   const std::vector<double>& a1, const std::vector<double>& v1, double d, double s) {
  const double s2 = s * s, s3 = s2 * s;
  std::vector<double> out(v0.size());
  for (size_t i = 0; i < v0.size(); ++i)
    out[i] = (2 * s3 - 3 * s2 + 1) * v0[i] + (s3 - 2 * s2 + s) * d * b0[i] + (-2 * s3 + 3 * s2) * v1[i] +
             (s3 - s2) * d * a1[i];
  return out;
}

/// One animation channel as the tests wrote it.
struct Track {
  int node;
  std::string path;           ///< "translation", "rotation" or "scale"
  std::string interpolation;  ///< "LINEAR", "STEP" or "CUBICSPLINE"
  std::vector<float> times, values;

  /// The value at `seconds` by the tests' own formulas: clamped to the first and last
  /// keyframe; rotations normalised (keyframes first, the result too).
  std::vector<double> at(double seconds) const {
    const size_t n = path == "rotation" ? 4 : 3, keys = times.size();
    const bool cubic = interpolation == "CUBICSPLINE";
    const auto element = [&](size_t e) {
      std::vector<double> v(values.begin() + long(e * n), values.begin() + long(e * n + n));
      return v;
    };
    const auto value = [&](size_t k) {
      const std::vector<double> v = element(cubic ? 3 * k + 1 : k);
      return n == 4 ? unit(v) : v;
    };
    if (seconds <= times.front()) return value(0);
    if (seconds >= times.back()) return value(keys - 1);
    size_t k = 0;
    while (!(seconds < times[k + 1])) ++k;
    const double d = double(times[k + 1]) - double(times[k]), s = (seconds - double(times[k])) / d;
    if (interpolation == "STEP") return value(k);
    if (!cubic) return n == 4 ? slerp(value(k), value(k + 1), s) : lerp(value(k), value(k + 1), s);
    const std::vector<double> p = hermite(value(k), element(3 * k + 2), element(3 * (k + 1)), value(k + 1), d, s);
    return n == 4 ? unit(p) : p;
  }
};

/// A glTF model and the channels it animates by.
struct AnimatedGltf {
  tinygltf::Model model;
  std::vector<Track> tracks;

  /// The same file at `seconds` without animations: each animated node's translation,
  /// rotation and scale replaced by its tracks' values then (Track::at).
  tinygltf::Model still(double seconds) const {
    tinygltf::Model m = model;
    m.animations.clear();
    for (const Track& t : tracks) {
      tinygltf::Node& node = m.nodes[size_t(t.node)];
      const std::vector<double> v = t.at(seconds);
      if (t.path == "translation") node.translation = v;
      if (t.path == "rotation") node.rotation = v;
      if (t.path == "scale") node.scale = v;
    }
    return m;
  }
};

/// Adds `t` to builder `b` (GltfBuilder::animate, animation 0) and to `out`.
inline void add_track(GltfBuilder& b, AnimatedGltf& out, Track t) {
  b.animate(t.node, t.path, t.times, t.values, t.interpolation);
  out.tracks.push_back(std::move(t));
}

/// A rotation of `degrees` about `axis` as a quaternion (x, y, z, w), rounded to floats.
inline std::vector<float> turn(Vec3d axis, double degrees) {
  axis = normalize(axis);
  const double h = degrees * kPi / 360.0;
  return {float(axis.x * std::sin(h)), float(axis.y * std::sin(h)), float(axis.z * std::sin(h)), float(std::cos(h))};
}

/// A scene of two meshes placed by animated and still nodes, every interpolation and property
/// animated, for comparing a posed scene with its still copy (AnimatedGltf::still):
/// - "quad" (a unit square about the origin) placed by node 1, animated (translation linear,
///   rotation linear, scale by a cubic spline over [0, 1] s) below node 0 (still, turned and
///   moved), and by node 2 (still);
/// - "triangle" placed by node 4 (still) below node 3 (rotation linear over [0, 1] s through
///   three keyframes), by node 5 (still) and by node 6 (translation by steps at 0, 0.25 and
///   0.5 s).
/// Every mesh is placed by several nodes, so its still copy instances it too, with the same
/// instances in the same order. No camera, no lights.
inline AnimatedGltf animated_scene() {
  GltfBuilder b;
  AnimatedGltf out;
  const int quad = b.mesh(
      {GltfBuilder::primitive(b.vectors({{-0.5f, -0.5f, 0}, {0.5f, -0.5f, 0}, {0.5f, 0.5f, 0}, {-0.5f, 0.5f, 0}}),
                              b.indices({0, 1, 2, 0, 2, 3}, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT))},
      "quad");
  const int triangle = b.mesh(
      {GltfBuilder::primitive(b.vectors({{-0.6f, -0.4f, 0.1f}, {0.7f, -0.3f, 0}, {0.1f, 0.8f, -0.2f}}))}, "triangle");
  const std::vector<float> r0 = turn({0, 1, 0}, 30);
  b.node(-1, {0.5, 0, -1}, {r0[0], r0[1], r0[2], r0[3]}, {}, {1});
  b.node(quad);
  b.node(quad, {-3, 0, 0});
  b.node(-1, {}, {}, {}, {4});
  b.node(triangle, {0, 1, 0}, {}, {0.5, 0.5, 0.5});
  b.node(triangle, {3, -2, 0});
  b.node(triangle);
  b.scene({0, 2, 3, 5, 6});
  add_track(b, out, {1, "translation", "LINEAR", {0, 1}, {0, 0, 0, 2, 1, 0}});
  add_track(b, out, {1, "rotation", "LINEAR", {0, 1}, {0, 0, 0, 1, 0, 0, 1, 0}});
  // In-tangent, value, out-tangent per keyframe; the first in-tangent and the last
  // out-tangent are never used (9s).
  add_track(b, out, {1, "scale", "CUBICSPLINE", {0, 1}, {9, 9, 9, 1, 1, 1, 1, 0, 2, 0, 4, -2, 2, 2, 2, 9, 9, 9}});
  std::vector<float> rotations = turn({1, 0, 0}, 0);
  for (const double degrees : {40.0, 80.0})
    for (const float c : turn({1, 0, 0}, degrees)) rotations.push_back(c);
  add_track(b, out, {3, "rotation", "LINEAR", {0, 0.5f, 1}, rotations});
  add_track(b, out, {6, "translation", "STEP", {0, 0.25f, 0.5f}, {0, -3, 0, 1, -3, 0, 2, -3, 0}});
  out.model = std::move(b.model);
  return out;
}

}  // namespace rp::test
