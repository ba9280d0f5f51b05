/// glTF animations (io/loaders/gltf_reader.h): every channel of every animation as a curve of
/// its node's translation, rotation or scale, the sampler's accessors checked as glTF 2.0
/// states them (its "Animations" section) before a keyframe is used.

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <vector>

#include "base/error.h"
#include "io/loaders/gltf_check.h"
#include "io/loaders/gltf_reader.h"

namespace rp {
namespace {

constexpr const char* kPropertyNames[] = {"translation", "rotation", "scale"};

}  // namespace

void GltfReader::read_animations() {
  node_curves_.assign(m_.nodes.size(), {-1, -1, -1});
  std::vector<std::array<std::string, 3>> claimed(m_.nodes.size());  // the channel animating each
  std::set<int> nodes;
  counts_.animations = m_.animations.size();
  for (size_t a = 0; a < m_.animations.size(); ++a) {
    const tinygltf::Animation& animation = m_.animations[a];
    for (size_t c = 0; c < animation.channels.size(); ++c) {
      const tinygltf::AnimationChannel& channel = animation.channels[c];
      const std::string cp = cat("$.animations[", a, "].channels[", c, "]");
      ++counts_.channels;
      at(animation.samplers, channel.sampler, cp + ".sampler");
      const tinygltf::Node& node = at(m_.nodes, channel.target_node, cp + ".target.node");
      if (channel.target_path == "weights")
        fail(cp + ".target.path", "\"weights\": morph-target animation is not supported");
      const auto name = std::find(std::begin(kPropertyNames), std::end(kPropertyNames), channel.target_path);
      guaranteed(name != std::end(kPropertyNames), cp + ".target.path");
      const auto property = AnimatedProperty(name - std::begin(kPropertyNames));
      const int n = channel.target_node;
      if (!node.matrix.empty())
        fail(cp + ".target.node", cat("node ", n,
                                      " is placed by a \"matrix\", which glTF does not animate (an animated node has "
                                      "translation, rotation and scale)"));
      std::string& other = claimed[size_t(n)][size_t(property)];
      if (!other.empty())
        fail(cp + ".target", cat("node ", n, "'s ", channel.target_path, " is animated by ", other,
                                 " too (every animation plays at once, so a node's property may have one channel)"));
      other = cp;
      node_curves_[size_t(n)][size_t(property)] = int(curves_.size());
      curves_.push_back(curve(int(a), channel.sampler, property, cp));
      nodes.insert(n);
    }
  }
  counts_.nodes = nodes.size();
}

AnimationCurve GltfReader::curve(int a, int s, AnimatedProperty property, const std::string& cp) const {
  const tinygltf::AnimationSampler& sampler = m_.animations[size_t(a)].samplers[size_t(s)];
  const std::string sp = cat("$.animations[", a, "].samplers[", s, "]");
  AnimationCurve out;
  out.property = property;
  const std::string& kind = sampler.interpolation;
  guaranteed(kind == "LINEAR" || kind == "STEP" || kind == "CUBICSPLINE", sp + ".interpolation");
  out.interpolation = kind == "STEP"     ? Interpolation::step
                      : kind == "LINEAR" ? Interpolation::linear
                                         : Interpolation::cubic_spline;

  // Keyframe times: scalar floats, finite, strictly increasing.
  const std::string ip = sp + ".input";
  out.times = numbers(view(sampler.input, ip, TINYGLTF_TYPE_SCALAR, {TINYGLTF_COMPONENT_TYPE_FLOAT}));
  for (size_t k = 0; k < out.times.size(); ++k) {
    if (!std::isfinite(out.times[k])) fail(ip, cat("keyframe ", k, ": its time is not a finite number"));
    if (k > 0 && !(out.times[k] > out.times[k - 1]))
      fail(ip, cat("keyframe ", k, ": its time ", out.times[k], " s is not after keyframe ", k - 1, "'s (",
                   out.times[k - 1], " s); times must increase"));
  }

  // Values: VEC3 floats for a translation or scale; VEC4 floats or normalized integers for a
  // rotation (glTF 2.0's accessor types for each path).
  const bool rotation = property == AnimatedProperty::rotation;
  const std::string op = sp + ".output";
  const std::string use = cat(op, " (", kPropertyNames[size_t(property)], " of ", cp, ")");
  const View values =
      rotation
          ? view(sampler.output, use, TINYGLTF_TYPE_VEC4,
                 {TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_COMPONENT_TYPE_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE,
                  TINYGLTF_COMPONENT_TYPE_SHORT, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT})
          : view(sampler.output, use, TINYGLTF_TYPE_VEC3, {TINYGLTF_COMPONENT_TYPE_FLOAT});
  const tinygltf::Accessor& acc = m_.accessors[size_t(sampler.output)];
  if (values.component_type != TINYGLTF_COMPONENT_TYPE_FLOAT && !acc.normalized)
    fail(cat("$.accessors[", sampler.output, "].normalized"),
         cat(use, " reads integer components as normalized numbers only (\"normalized\": true)"));
  const bool cubic = out.interpolation == Interpolation::cubic_spline;
  const size_t per_key = cubic ? 3 : 1;
  if (values.count != out.times.size() * per_key)
    fail(op, cat("accessor ", sampler.output, " has ", values.count, " elements for ", out.times.size(), " keyframes; ",
                 kind, " needs ", cubic ? "3 per keyframe (in-tangent, value, out-tangent), " : "",
                 out.times.size() * per_key));
  out.values = numbers(values);
  const size_t n = out.components();
  for (size_t e = 0; e < values.count; ++e) {
    const std::span<double> element(out.values.data() + e * n, n);
    if (!std::all_of(element.begin(), element.end(), [](double x) { return std::isfinite(x); }))
      fail(op, cat("element ", e, " is not finite"));
    if (!rotation || (cubic && e % 3 != 1)) continue;  // tangents are not rotations
    if (const std::optional<std::string> problem = rotation_problem(element))
      fail(op, cat("element ", e, ": ", *problem));
    const double len = std::sqrt(element[0] * element[0] + element[1] * element[1] + element[2] * element[2] +
                                 element[3] * element[3]);
    for (double& x : element) x /= len;
  }
  return out;
}

}  // namespace rp
