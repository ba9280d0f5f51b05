#pragma once
/// A scene file's node animation, sampled at a time (glTF 2.0's animations: which of them are
/// read and what is refused, the top of io/loaders/gltf.cpp).
///
/// Every animation of a file plays at once, from 0 s: a curve (an animation sampler as a
/// channel uses it) replaces one property of one node, its translation, rotation or scale, and
/// a property no curve animates keeps the node's own value. apply() samples every curve at a
/// time, composes the placements of the nodes it moves (parent * child in double, as the
/// loader composes them) and moves what those nodes place: instances (Scene::set_transform),
/// KHR_lights_punctual lights (Scene::set_light) and the camera (Scene::set_camera). The scene
/// a loader returns is the rest pose, the nodes' own values, which need not be the pose at 0 s.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/affine.h"
#include "core/scene.h"

namespace rp {

/// A node's own placement: translation, rotation (a quaternion x, y, z, w) and scale.
struct NodeTrs {
  std::array<double, 3> translation{0, 0, 0};
  std::array<double, 4> rotation{0, 0, 0, 1};  ///< made unit length by matrix()
  std::array<double, 3> scale{1, 1, 1};

  /// T * R * S in double, the rotation divided by its length first: the one formula of a
  /// node's transform, for the loader's rest pose and every pose apply() makes, so that a pose
  /// and a still file holding the same numbers give the same bits.
  Affine3d matrix() const;
};

/// What a node at `to_world` makes of what it places, by glTF's conventions, for the loader's
/// rest pose and every pose apply() makes alike. A camera: eye at the node's origin, looking
/// at the point one unit down its -Z, up its +Y, the model and field of view of `camera`;
/// nothing when that makes no camera (a field of view outside (0, 180) degrees, an eye or
/// look-at point outside the coordinate range, no view direction, or an up along it).
std::optional<CameraDesc> node_camera(const Affine3d& to_world, CameraDesc camera);
/// A point light at the node's origin, of `intensity`.
PointLight node_point_light(const Affine3d& to_world, const Vec3f& intensity);
/// A directional light along the node's -Z, of `irradiance`.
DirectionalLight node_directional_light(const Affine3d& to_world, const Vec3f& irradiance);

/// How a curve passes between its keyframes (glTF 2.0, section 3.11 and Appendix C).
enum class Interpolation : uint8_t {
  linear,        ///< a straight line; a rotation by slerp along the shorter arc
  step,          ///< the value of the last keyframe at or before the time
  cubic_spline,  ///< the cubic Hermite spline of the keyframes' values and tangents
};

/// The node property a curve animates.
enum class AnimatedProperty : uint8_t { translation, rotation, scale };

/// An animation sampler as a channel reads it.
struct AnimationCurve {
  AnimatedProperty property = AnimatedProperty::translation;
  Interpolation interpolation = Interpolation::linear;
  /// Keyframe times in seconds: at least one, finite, strictly increasing.
  std::vector<double> times;
  /// components() numbers per keyframe, keyframe after keyframe; cubic_spline: three groups
  /// per keyframe, in-tangent, value, out-tangent (tangents in units per second). A rotation's
  /// values (not its tangents) are unit quaternions.
  std::vector<double> values;

  /// 4 for a rotation (x, y, z, w), else 3.
  size_t components() const { return property == AnimatedProperty::rotation ? 4 : 3; }
};

/// The curve's value at `seconds` (components() numbers; a fourth 0 for 3): before its first
/// keyframe the first value, after its last the last (glTF's clamping). linear: lerp, a
/// rotation slerp along the shorter arc; step: the keyframe at or before; cubic_spline: the
/// Hermite spline p(s) = (2s^3 - 3s^2 + 1) v_k + (s^3 - 2s^2 + s) d b_k + (-2s^3 + 3s^2) v_k+1
/// + (s^3 - s^2) d a_k+1, where d is the keyframes' interval, s = (t - t_k) / d, b_k the
/// out-tangent of keyframe k and a_k+1 the in-tangent of the next. A rotation's result is
/// normalised.
std::array<double, 4> sample(const AnimationCurve& curve, double seconds);

/// A node whose placement the animation changes: an animated node, or one below an animated
/// node. SceneAnimation::nodes() lists parents before children.
struct AnimatedNode {
  std::string path;  ///< the node in the file, for messages: "$.nodes[7]"
  int parent = -1;   ///< its parent's index in SceneAnimation::nodes(), or -1
  Affine3d base;     ///< parent == -1: its parent's node-to-world, which never moves
  /// The curve of its translation, rotation and scale (AnimatedProperty's order), or -1.
  std::array<int, 3> curves{-1, -1, -1};
  NodeTrs rest;    ///< an animated node's own values, for the properties no curve replaces
  Affine3d local;  ///< a node no curve animates (below an animated one): its own transform

  bool animated() const { return curves[0] >= 0 || curves[1] >= 0 || curves[2] >= 0; }
};

/// What an animated node places, which moves with it.
struct AnimatedTarget {
  enum class Kind : uint8_t { instance, point_light, directional_light, camera };
  Kind kind = Kind::instance;
  uint32_t node = 0;   ///< index in SceneAnimation::nodes()
  uint32_t index = 0;  ///< the instance's or light's index in the Scene (0 for the camera)
  Vec3f power{1.0f};   ///< a light's intensity (point) or irradiance (directional)
  CameraDesc camera;   ///< the camera's model and field of view; apply() places it
};

/// How much a file animates, as `raypack info` reports it.
struct AnimationCounts {
  size_t animations = 0;  ///< of the file
  size_t channels = 0;    ///< of every animation
  size_t nodes = 0;       ///< distinct nodes the channels animate
};

/// The animation of one loaded scene: its curves, the nodes they move and what those place.
/// Made by the loader (io/loaders/load.h) beside the Scene it describes; apply() must be given
/// that Scene (or a copy of it), whose instances and lights keep the indices the loader gave.
class SceneAnimation {
 public:
  /// No animation: empty(), apply() changes nothing.
  SceneAnimation() = default;
  /// The animation of `file` (named in apply()'s messages).
  SceneAnimation(std::string file, std::vector<AnimationCurve> curves, std::vector<AnimatedNode> nodes,
                 std::vector<AnimatedTarget> targets, AnimationCounts counts);

  /// True when the file has no animation channel.
  bool empty() const { return counts_.channels == 0; }
  /// Seconds of the longest animation: the last keyframe time of every curve, at least 0.
  double duration() const { return duration_; }
  const AnimationCounts& counts() const { return counts_; }
  const std::vector<AnimationCurve>& curves() const { return curves_; }
  const std::vector<AnimatedNode>& nodes() const { return nodes_; }
  const std::vector<AnimatedTarget>& targets() const { return targets_; }

  /// The node-to-world map of every node of nodes() at `seconds` (any finite time; each curve
  /// clamps it), by index.
  std::vector<Affine3d> node_to_world(double seconds) const;

  /// Poses `scene` at `seconds`: every target moved where its node is then. An instance
  /// whose transform is unchanged is left alone (its version does not move). Throws rp::Error
  /// naming the file, the node and the time when the pose cannot be placed (a transform that is
  /// singular or outside the coordinate range, a camera with no direction), or for a time that
  /// is not finite; the instances and lights set before the failure keep their new values.
  void apply(Scene& scene, double seconds) const;

 private:
  std::string file_;
  std::vector<AnimationCurve> curves_;
  std::vector<AnimatedNode> nodes_;
  std::vector<AnimatedTarget> targets_;
  AnimationCounts counts_;
  double duration_ = 0.0;
};

/// A scene file's scene at its rest pose and its animation (empty for a still file).
struct AnimatedScene {
  Scene scene;
  SceneAnimation animation;
};

}  // namespace rp
