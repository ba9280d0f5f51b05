/// glTF node animation (io/loaders/animation.h, io/loaders/gltf_animation.cpp) on files the
/// tests write: each interpolation of each property sampled between keyframes against a closed
/// form or the tests' own formulas (tests/support/animated_gltf.h: lerp, textbook slerp, the
/// Hermite basis written out), clamping outside the keyframes, normalized integer rotations,
/// the hierarchy composed parent * child, every animation playing at once, cameras and lights
/// following their nodes, a posed scene against its still copy, the rest pose load_scene
/// gives, and the one-line message of every refusal: hostile samplers and channels, skins and
/// morph targets.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "base/error.h"
#include "gltf_scratch.h"
#include "io/loaders/load.h"
#include "scratch.h"
#include "tests/support/animated_gltf.h"
#include "tests/support/gltf_files.h"

namespace rp {
namespace {

using test::error_loading;
using test::GltfBuilder;
using test::GltfForm;
using test::scratch;
using test::written;

/// `b` written as animation/`name` and loaded with its animation.
AnimatedScene load(const GltfBuilder& b, const std::string& name) {
  return load_animated_scene(written(b.model, "animation/" + name, GltfForm::embedded));
}

/// A mesh of one triangle.
int triangle(GltfBuilder& b) { return b.mesh({GltfBuilder::primitive(b.vectors({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}))}); }

/// A triangle placed by node 0 (at `rest`, when given), whose `path` one channel animates by
/// keyframe `times` and `values` (GltfBuilder::animate).
GltfBuilder one_animated_node(const std::string& path, const std::vector<float>& times,
                              const std::vector<float>& values, const std::string& interpolation = "LINEAR",
                              std::vector<double> rest = {}) {
  GltfBuilder b;
  b.scene({b.node(triangle(b), std::move(rest))});
  b.animate(0, path, times, values, interpolation);
  return b;
}

/// `q` as doubles.
std::vector<double> doubles(const std::vector<float>& q) { return {q.begin(), q.end()}; }

/// A rotation of `degrees` about `axis`, in double.
std::vector<double> turn(Vec3d axis, double degrees) {
  axis = normalize(axis);
  const double h = degrees * kPi / 360.0;
  return {axis.x * std::sin(h), axis.y * std::sin(h), axis.z * std::sin(h), std::cos(h)};
}

void expect_near(const Affine3d& got, const Affine3d& want, double tolerance, const std::string& what) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 4; ++j) EXPECT_NEAR(got.m[i][j], want.m[i][j], tolerance) << what << ": entry " << i << j;
}

/// The translation of an instance's transform.
Vec3d translation(const Instance& in) { return Vec3d(Affine3d(in.object_to_world).point({0, 0, 0})); }

TEST(GltfAnimation, LinearTranslationFollowsTheLineBetweenKeyframesAndHoldsItsEndsOutside) {
  AnimatedScene s =
      load(one_animated_node("translation", {1, 3}, {0, 0, 0, 4, 2, -2}, "LINEAR", {5, 5, 5}), "linear.gltf");
  // Placed once, by an animated node: an instanced mesh and its instance, at the rest pose.
  ASSERT_EQ(s.scene.meshes().size(), 1u);
  EXPECT_TRUE(s.scene.is_instanced(0));
  ASSERT_EQ(s.scene.instances().size(), 1u);
  EXPECT_EQ(translation(s.scene.instances()[0]), Vec3d(5, 5, 5));
  EXPECT_EQ(s.animation.duration(), 3.0);
  const std::vector<double> first{0, 0, 0}, last{4, 2, -2};
  const std::pair<double, std::vector<double>> cases[] = {
      {-1, first}, {0, first}, {1, first}, {1.5, test::lerp(first, last, 0.25)}, {2.5, test::lerp(first, last, 0.75)},
      {3, last},   {7, last}};
  for (const auto& [t, want] : cases) {
    SCOPED_TRACE(t);
    expect_near(s.animation.node_to_world(t)[0], test::node_transform(want, {}, {}), 1e-12, "node");
    s.animation.apply(s.scene, t);
    EXPECT_LE(length(translation(s.scene.instances()[0]) - Vec3d(want[0], want[1], want[2])), 1e-6);
  }
}

TEST(GltfAnimation, LinearRotationIsTheSlerpAlongTheShorterArc) {
  // Keyframes 10 and 130 degrees about one axis, the second stored negated (q and -q are one
  // rotation): a quarter of the way is 40 degrees about that axis, a closed form; the long way
  // round would turn the other way.
  GltfBuilder b;
  const Vec3d axis(1, 2, 3);
  const std::vector<float> q0 = test::turn(axis, 10), q1 = test::turn(axis, 130);
  std::vector<float> keys = q0;
  for (const float c : q1) keys.push_back(-c);
  const int n = b.node(triangle(b));
  b.scene({n});
  b.animate(n, "rotation", {0, 1}, keys);
  // Another pair, 20 degrees about x to 140 about (0, 1, 1), against the textbook slerp.
  const std::vector<float> p0 = test::turn({1, 0, 0}, 20), p1 = test::turn({0, 1, 1}, 140);
  std::vector<float> other = p0;
  other.insert(other.end(), p1.begin(), p1.end());
  const int m = b.node(triangle(b));
  b.model.scenes[0].nodes.push_back(m);
  b.animate(m, "rotation", {0, 2}, other);
  const AnimatedScene s = load(b, "slerp.gltf");
  for (const double s_ : {0.25, 0.5, 0.9}) {
    SCOPED_TRACE(s_);
    // Float keyframes: within 1e-6 of the exact angle.
    expect_near(s.animation.node_to_world(s_)[0], test::node_transform({}, turn(axis, 10 + 120 * s_), {}), 1e-6,
                "closed form");
    const std::vector<double> want = test::slerp(test::unit(doubles(p0)), test::unit(doubles(p1)), s_);
    expect_near(s.animation.node_to_world(2 * s_)[1], test::node_transform({}, want, {}), 1e-12, "textbook slerp");
  }
}

TEST(GltfAnimation, StepHoldsEachKeyframeUntilTheNext) {
  const AnimatedScene s = load(one_animated_node("scale", {0, 1, 2}, {1, 1, 1, 2, 3, 4, 5, 6, 7}, "STEP"), "step.gltf");
  const std::pair<double, std::vector<double>> cases[] = {{-5, {1, 1, 1}}, {0, {1, 1, 1}},   {0.999, {1, 1, 1}},
                                                          {1, {2, 3, 4}},  {1.5, {2, 3, 4}}, {2, {5, 6, 7}},
                                                          {9, {5, 6, 7}}};
  for (const auto& [t, want] : cases)
    EXPECT_TRUE(s.animation.node_to_world(t)[0] == test::node_transform({}, {}, want)) << t;
}

TEST(GltfAnimation, CubicSplineIsTheHermiteCurveWithTangentsScaledByTheInterval) {
  // Keyframes at 1 s and 3 s (an interval of 2): v0 (1, 0, 0) leaving along b0 (0, 2, 0),
  // v1 (3, 1, 0) arriving along a1 (1, 0, 4); the first in-tangent and the last out-tangent
  // (7s) are never used. At 1.5 s, s = 1/4: h00 = 0.84375, h10 = 0.140625, h01 = 0.15625,
  // h11 = -0.046875, so p = h00 v0 + 2 h10 b0 + h01 v1 + 2 h11 a1 = (1.21875, 0.71875, -0.375).
  const AnimatedScene s = load(
      one_animated_node("translation", {1, 3}, {7, 7, 7, 1, 0, 0, 0, 2, 0, 1, 0, 4, 3, 1, 0, 7, 7, 7}, "CUBICSPLINE"),
      "cubic.gltf");
  EXPECT_TRUE(s.animation.node_to_world(1.5)[0] == test::node_transform({1.21875, 0.71875, -0.375}, {}, {}));
  EXPECT_TRUE(s.animation.node_to_world(0)[0] == test::node_transform({1, 0, 0}, {}, {}));
  EXPECT_TRUE(s.animation.node_to_world(3)[0] == test::node_transform({3, 1, 0}, {}, {}));
  EXPECT_TRUE(s.animation.node_to_world(4)[0] == test::node_transform({3, 1, 0}, {}, {}));
  const double t = 2.2;  // s = 0.6, by the tests' Hermite
  const std::vector<double> want = test::hermite({1, 0, 0}, {0, 2, 0}, {1, 0, 4}, {3, 1, 0}, 2.0, 0.6);
  expect_near(s.animation.node_to_world(t)[0], test::node_transform(want, {}, {}), 1e-12, "s = 0.6");
}

TEST(GltfAnimation, ACubicSplineRotationIsNormalised) {
  const std::vector<float> q0 = test::turn({0, 0, 1}, 0), q1 = test::turn({0, 0, 1}, 100);
  const std::vector<float> t0{0.5f, 0, 0.3f, 0}, t1{0, 0.4f, 0, -0.2f};
  std::vector<float> keys = t0;
  for (const auto* part : {&q0, &t0, &t1, &q1, &t1}) keys.insert(keys.end(), part->begin(), part->end());
  const AnimatedScene s = load(one_animated_node("rotation", {0, 1}, keys, "CUBICSPLINE"), "cubic-rotation.gltf");
  ASSERT_EQ(s.animation.curves().size(), 1u);
  const std::array<double, 4> q = sample(s.animation.curves()[0], 0.3);
  EXPECT_NEAR(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3], 1.0, 1e-15);
  const std::vector<double> raw =
      test::hermite(test::unit(doubles(q0)), doubles(t0), doubles(t1), test::unit(doubles(q1)), 1.0, 0.3);
  const std::vector<double> want = test::unit(raw);
  for (size_t i = 0; i < 4; ++i) EXPECT_NEAR(q[i], want[i], 1e-12) << i;
}

TEST(GltfAnimation, NormalizedIntegerRotationsAreReadAsGltfMapsThem) {
  // Signed bytes: c / 127, and -128 clamped to -1. Keyframes (0, 0, 0, 127): no turn;
  // (0, 127, 0, 0): half a turn about y; (-128, 0, 0, 0): half a turn about x. Unsigned shorts
  // (0, 0, 65535, 0): half a turn about z.
  GltfBuilder b;
  const int n = b.node(triangle(b)), m = b.node(triangle(b));
  b.scene({n, m});
  const std::vector<int8_t> bytes{0, 0, 0, 127, 0, 127, 0, 0, -128, 0, 0, 0};
  const int signed_out =
      b.accessor(b.view(bytes.data(), bytes.size()), TINYGLTF_COMPONENT_TYPE_BYTE, TINYGLTF_TYPE_VEC4, 3);
  b.model.accessors[size_t(signed_out)].normalized = true;
  b.animate(n, "rotation", b.floats({0, 1, 2}, TINYGLTF_TYPE_SCALAR), signed_out, "STEP");
  const std::vector<uint16_t> shorts{0, 0, 65535, 0};
  const int unsigned_out =
      b.accessor(b.view(shorts.data(), 8), TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, TINYGLTF_TYPE_VEC4, 1);
  b.model.accessors[size_t(unsigned_out)].normalized = true;
  b.animate(m, "rotation", b.floats({0}, TINYGLTF_TYPE_SCALAR), unsigned_out, "LINEAR");
  const AnimatedScene s = load(b, "integer-rotations.gltf");
  const auto diagonal = [](double x, double y, double z) {
    Affine3d a;
    a.m[0][0] = x;
    a.m[1][1] = y;
    a.m[2][2] = z;
    return a;
  };
  EXPECT_TRUE(s.animation.node_to_world(0)[0] == diagonal(1, 1, 1));
  EXPECT_TRUE(s.animation.node_to_world(1)[0] == diagonal(-1, 1, -1));
  EXPECT_TRUE(s.animation.node_to_world(2)[0] == diagonal(1, -1, -1));
  EXPECT_TRUE(s.animation.node_to_world(0)[1] == diagonal(-1, -1, 1));
}

TEST(GltfAnimation, AnAnimatedNodesMeshesAreInstancedAndComposedBelowTheirAncestors) {
  // Node 0 (at (1, 0, 0), turning 0 to 90 degrees about z over 1 s) places nothing; its child
  // node 1 (at (2, 0, 0), scale 1/2) places "moved". Node 2, still, places "still" once: baked.
  GltfBuilder b;
  const int moved = triangle(b), still = triangle(b);
  const int child = b.node(moved, {2, 0, 0}, {}, {0.5, 0.5, 0.5});
  const int parent = b.node(-1, {1, 0, 0}, {}, {}, {child});
  b.scene({parent, b.node(still, {0, 0, 4})});
  std::vector<float> keys = test::turn({0, 0, 1}, 0);
  for (const float c : test::turn({0, 0, 1}, 90)) keys.push_back(c);
  b.animate(parent, "rotation", {0, 1}, keys);
  AnimatedScene s = load(b, "hierarchy.gltf");
  ASSERT_EQ(s.scene.meshes().size(), 2u);
  EXPECT_TRUE(s.scene.is_instanced(0));
  EXPECT_FALSE(s.scene.is_instanced(1));
  EXPECT_EQ(Vec3d(s.scene.meshes()[1].positions[1]), Vec3d(1, 0, 4));
  ASSERT_EQ(s.animation.nodes().size(), 2u);  // the animated node and the node below it
  EXPECT_EQ(s.animation.targets().size(), 1u);
  s.animation.apply(s.scene, 0.5);
  const Affine3d want = compose(test::node_transform({1, 0, 0}, turn({0, 0, 1}, 45), {}),
                                test::node_transform({2, 0, 0}, {}, {0.5, 0.5, 0.5}));
  expect_near(s.animation.node_to_world(0.5)[1], want, 1e-7, "node 1");
  expect_near(Affine3d(s.scene.instances()[0].object_to_world), want, 1e-6, "instance");
  // The child's origin: (1, 0, 0) + R(45) (2, 0, 0).
  EXPECT_LE(length(translation(s.scene.instances()[0]) - Vec3d(1 + std::sqrt(2.0), std::sqrt(2.0), 0)), 1e-6);
}

TEST(GltfAnimation, EveryAnimationPlaysAtOnceAndTheLongestIsTheDuration) {
  GltfBuilder b;
  const int mesh = triangle(b);
  const int a = b.node(mesh), c = b.node(mesh, {0, 3, 0});
  b.scene({a, c});
  b.animate(a, "translation", {0, 2}, {0, 0, 0, 4, 0, 0}, "LINEAR", 0);
  b.animate(c, "translation", {0.5f, 4.5f}, {0, 3, 0, 0, 3, 8}, "LINEAR", 1);
  AnimatedScene s = load(b, "two-animations.gltf");
  EXPECT_EQ(s.animation.duration(), 4.5);
  EXPECT_EQ(s.animation.counts().animations, 2u);
  EXPECT_EQ(s.animation.counts().channels, 2u);
  EXPECT_EQ(s.animation.counts().nodes, 2u);
  ASSERT_EQ(s.scene.instances().size(), 2u);  // one mesh, two nodes
  s.animation.apply(s.scene, 1.0);
  EXPECT_EQ(translation(s.scene.instances()[0]), Vec3d(2, 0, 0));
  EXPECT_EQ(translation(s.scene.instances()[1]), Vec3d(0, 3, 1));
}

TEST(GltfAnimation, CamerasAndLightsBelowAnAnimatedNodeFollowIt) {
  // Node 0 moves from (0, 0, 5) to (0, 0, 9) over 2 s; below it a camera, a point light 1 up,
  // and a sun whose own rotation turns from -90 to 0 degrees about x over 1 s.
  // camera_and_lights_gltf's nodes: 0 the camera used, 1 another camera, 2 the triangle, 3
  // the point light, 4 the sun, 5 the spot.
  GltfBuilder b = test::camera_and_lights_gltf();
  const int carrier = b.node(-1, {0, 0, 5}, {}, {}, {0, 3, 4});
  b.model.nodes[0].translation.clear();      // the camera at the carrier's origin
  b.model.nodes[3].translation = {0, 1, 0};  // the point light
  b.model.scenes[0].nodes = {2, carrier, 1, 5};
  b.animate(carrier, "translation", {0, 2}, {0, 0, 5, 0, 0, 9});
  std::vector<float> keys = test::turn({1, 0, 0}, -90);
  for (const float c : test::turn({1, 0, 0}, 0)) keys.push_back(c);
  b.animate(4, "rotation", {0, 1}, keys);
  AnimatedScene s = load(b, "camera-lights.gltf");
  s.animation.apply(s.scene, 1.0);
  ASSERT_TRUE(s.scene.camera().has_value());
  EXPECT_EQ(s.scene.camera()->eye, Vec3f(0, 0, 7));
  EXPECT_EQ(s.scene.camera()->look_at, Vec3f(0, 0, 6));
  EXPECT_FLOAT_EQ(s.scene.camera()->vfov_degrees, 45.0f);
  EXPECT_EQ(s.scene.point_lights()[0].position, Vec3f(0, 1, 7));
  EXPECT_EQ(s.scene.point_lights()[0].intensity, Vec3f(20.0f, 10.0f, 5.0f));
  EXPECT_EQ(s.scene.point_lights()[1].position, Vec3f(0, 4, 0));  // the spot, not below the carrier
  EXPECT_LE(length(Vec3d(s.scene.directional_lights()[0].direction) - Vec3d(0, 0, -1)), 1e-6);
  s.animation.apply(s.scene, 0.5);
  EXPECT_LE(length(Vec3d(s.scene.directional_lights()[0].direction) - normalize(Vec3d(0, -1, -1))), 1e-6);
}

TEST(GltfAnimation, LoadSceneGivesTheRestPoseAndOtherFormatsNoAnimation) {
  const GltfBuilder b = one_animated_node("translation", {0, 1}, {0, 0, 0, 1, 0, 0}, "LINEAR", {5, 0, 0});
  const Scene rest = load_scene(written(b.model, "animation/rest.gltf", GltfForm::embedded));
  ASSERT_EQ(rest.instances().size(), 1u);
  EXPECT_EQ(translation(rest.instances()[0]), Vec3d(5, 0, 0));
  const AnimatedScene obj =
      load_animated_scene(test::write_file("animation/still.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"));
  EXPECT_TRUE(obj.animation.empty());
  EXPECT_EQ(obj.animation.duration(), 0.0);
  EXPECT_TRUE(load_animated_scene("default").animation.empty());
}

TEST(GltfAnimation, AnInstanceThatDoesNotMoveKeepsItsVersion) {
  AnimatedScene s = load(one_animated_node("translation", {0, 1}, {0, 0, 0, 1, 0, 0}), "version.gltf");
  s.animation.apply(s.scene, 2.0);
  const uint64_t moved = s.scene.version();
  s.animation.apply(s.scene, 3.0);  // clamped: the same pose
  EXPECT_EQ(s.scene.version(), moved);
  s.animation.apply(s.scene, 0.5);
  EXPECT_GT(s.scene.version(), moved);
  EXPECT_EQ(s.scene.instances_version(), s.scene.version());
}

TEST(GltfAnimation, APosedSceneIsItsStillCopyAtThatTime) {
  const test::AnimatedGltf a = test::animated_scene();
  AnimatedScene posed = load_animated_scene(written(a.model, "animation/scene.gltf", GltfForm::embedded));
  EXPECT_EQ(posed.animation.counts().channels, 5u);
  EXPECT_EQ(posed.animation.counts().nodes, 3u);
  EXPECT_EQ(posed.animation.duration(), 1.0);
  for (const double t : {-1.0, 0.0, 0.2, 0.25, 0.5, 0.7, 1.0, 3.0}) {
    SCOPED_TRACE(t);
    posed.animation.apply(posed.scene, t);
    const Scene still = load_scene(written(a.still(t), "animation/still.gltf", GltfForm::embedded));
    ASSERT_EQ(still.instances().size(), posed.scene.instances().size());
    for (size_t i = 0; i < still.instances().size(); ++i) {
      EXPECT_EQ(still.instances()[i].mesh, posed.scene.instances()[i].mesh);
      expect_near(Affine3d(posed.scene.instances()[i].object_to_world), Affine3d(still.instances()[i].object_to_world),
                  1e-6, "instance " + std::to_string(i));
    }
  }
}

TEST(GltfAnimation, APoseThatCannotBePlacedIsRefusedNamingTheNodeAndTime) {
  AnimatedScene s = load(one_animated_node("scale", {0, 1}, {1, 1, 1, 0, 0, 0}), "vanish.gltf");
  const auto error_at = [&](double t) {
    std::string e = test::error_of([&] { s.animation.apply(s.scene, t); });
    const std::string dir = scratch().string() + "/";
    if (e.rfind(dir, 0) == 0) e.erase(0, dir.size());
    return e;
  };
  EXPECT_EQ(error_at(0.5), "no error");
  EXPECT_EQ(error_at(1.0),
            "animation/vanish.gltf: $.nodes[0] at 1 s: instance 0: the transform of mesh 'mesh 0' is not invertible");
  EXPECT_EQ(error_at(std::numeric_limits<double>::quiet_NaN()),
            "animation/vanish.gltf: the time nan s is not a finite number");
}

// ---- refusals: one line each, naming the file and the JSON path ----

/// A triangle placed by node 0, whose translation is animated (accessors 1 and 2: the times and
/// values of sampler 0), changed by `change`.
GltfBuilder animated_triangle(const std::function<void(GltfBuilder&)>& change = {}) {
  GltfBuilder b = one_animated_node("translation", {0, 1}, {0, 0, 0, 1, 0, 0});
  if (change) change(b);
  return b;
}

TEST(GltfAnimationErrors, HostileSamplersAndChannelsAreOneLineNamingTheFileAndJsonPath) {
  using nlohmann::json;
  const std::string sampler = "$.animations[0].samplers[0]", channel = "$.animations[0].channels[0]";
  const std::string output = sampler + ".output (translation of " + channel + ")";
  // Accessor `which` (1: the times, 2: the values) replaced by accessor `other`, made after it.
  const auto replace = [](GltfBuilder& b, size_t which, int other) {
    b.model.accessors[which] = b.model.accessors[size_t(other)];
  };
  const auto with_times = [&](std::vector<float> times) {
    return [=](GltfBuilder& b) { replace(b, 1, b.floats(times, TINYGLTF_TYPE_SCALAR)); };
  };
  const auto with_values = [&](std::vector<float> values, int type) {
    return [=](GltfBuilder& b) { replace(b, 2, b.floats(values, type)); };
  };
  struct Case {
    std::function<void(GltfBuilder&)> change;
    std::function<void(json&)> patch;
    std::string message;
  };
  const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
  const Case cases[] = {
      {{},
       [](json& d) { d["accessors"][1]["type"] = "VEC3"; },
       "$.accessors[1].type: " + sampler + ".input needs SCALAR elements"},
      {{},
       [](json& d) { d["accessors"][1]["componentType"] = 5123; },
       "$.accessors[1].componentType: 5123 is not a component type " + sampler + ".input can have (5126)"},
      {with_times({0, 0}),
       {},
       sampler + ".input: keyframe 1: its time 0 s is not after keyframe 0's (0 s); times must increase"},
      {with_times({1, 0.5f}),
       {},
       sampler + ".input: keyframe 1: its time 0.5 s is not after keyframe 0's (1 s); times must increase"},
      {with_times({0, nan}), {}, sampler + ".input: keyframe 1: its time is not a finite number"},
      {with_times({-inf, 0}), {}, sampler + ".input: keyframe 0: its time is not a finite number"},
      {with_values({0, 0, 0, 1, 0, 0, 2, 0, 0}, TINYGLTF_TYPE_VEC3),
       {},
       sampler + ".output: accessor 2 has 3 elements for 2 keyframes; LINEAR needs 2"},
      {{},
       [](json& d) { d["animations"][0]["samplers"][0]["interpolation"] = "CUBICSPLINE"; },
       sampler + ".output: accessor 2 has 2 elements for 2 keyframes; CUBICSPLINE needs 3 per keyframe (in-tangent, "
                 "value, out-tangent), 6"},
      {{},
       [](json& d) { d["accessors"][2]["type"] = "VEC4"; },
       "$.accessors[2].type: " + output + " needs VEC3 elements"},
      {{},
       [](json& d) { d["accessors"][2]["componentType"] = 5122; },
       "$.accessors[2].componentType: 5122 is not a component type " + output + " can have (5126)"},
      {{},
       [](json& d) { d["animations"][0]["channels"][0]["target"]["path"] = "rotation"; },
       "$.accessors[2].type: " + sampler + ".output (rotation of " + channel + ") needs VEC4 elements"},
      {with_values({0, 0, 0, inf, 0, 0}, TINYGLTF_TYPE_VEC3), {}, sampler + ".output: element 1 is not finite"},
      {[&](GltfBuilder& b) {
         b.model.animations[0].channels[0].target_path = "rotation";
         replace(b, 2, b.floats({0, 0, 0, 1, 0, 0, 0, 2}, TINYGLTF_TYPE_VEC4));
       },
       {},
       sampler + ".output: element 1: its length 2 is not 1 (a rotation is a unit quaternion, within 0.00769)"},
      {[&](GltfBuilder& b) {
         b.model.animations[0].channels[0].target_path = "rotation";
         const std::vector<int8_t> q{0, 0, 0, 127, 0, 0, 0, 127};
         replace(b, 2, b.accessor(b.view(q.data(), q.size()), TINYGLTF_COMPONENT_TYPE_BYTE, TINYGLTF_TYPE_VEC4, 2));
       },
       {},
       "$.accessors[2].normalized: " + sampler + ".output (rotation of " + channel +
           ") reads integer components as normalized numbers only (\"normalized\": true)"},
      {[&](GltfBuilder& b) {
         b.model.animations[0].channels[0].target_path = "rotation";
         const std::vector<uint32_t> q{0, 0, 0, 1, 0, 0, 0, 1};
         replace(
             b, 2,
             b.accessor(b.view(q.data(), q.size() * 4), TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, TINYGLTF_TYPE_VEC4, 2));
       },
       {},
       "$.accessors[2].componentType: 5125 is not a component type " + sampler + ".output (rotation of " + channel +
           ") can have (5126, 5120, 5121, 5122, 5123)"},
      {{},
       [](json& d) { d["animations"][0]["channels"][0]["sampler"] = 3; },
       channel + ".sampler: 3 names no sampler (1 samplers)"},
      {{},
       [](json& d) { d["animations"][0]["channels"][0]["target"]["node"] = 9; },
       channel + ".target.node: 9 names no node (1 nodes)"},
      {{},
       [](json& d) { d["animations"][0]["channels"][0]["target"].erase("node"); },
       channel + ".target: has no \"node\""},
      {{}, [](json& d) { d["animations"][0]["channels"][0].erase("target"); }, channel + ": has no \"target\""},
      {{}, [](json& d) { d["animations"][0].erase("channels"); }, "$.animations[0]: has no \"channels\""},
      {{},
       [](json& d) { d["animations"][0]["samplers"][0]["input"] = 7; },
       sampler + ".input: 7 names no accessor (3 accessors)"},
      {{},
       [](json& d) { d["animations"][0]["channels"][0]["target"]["path"] = "color"; },
       channel + ".target.path: \"color\" is not an animation path (translation, rotation, scale, weights)"},
      {{},
       [](json& d) { d["animations"][0]["samplers"][0]["interpolation"] = "CUBIC"; },
       sampler + ".interpolation: \"CUBIC\" is not an interpolation (LINEAR, STEP, CUBICSPLINE)"},
      {{},
       [](json& d) { d["animations"][0]["channels"][0]["target"]["path"] = "weights"; },
       channel + ".target.path: \"weights\": morph-target animation is not supported"},
      {[](GltfBuilder& b) {
         b.animate(0, "translation", {0, 1}, {0, 0, 0, 0, 1, 0}, "STEP", 1);
       },
       {},
       "$.animations[1].channels[0].target: node 0's translation is animated by " + channel +
           " too (every animation plays at once, so a node's property may have one channel)"},
      {[](GltfBuilder& b) { b.model.nodes[0].matrix = test::column_major(Affine3d{}); },
       {},
       channel + ".target.node: node 0 is placed by a \"matrix\", which glTF does not animate (an animated node has "
                 "translation, rotation and scale)"},
      {[](GltfBuilder& b) {
         b.model.nodes[0].scale = {0, 0, 0};
       },
       {},
       "$.nodes[0]: its rest transform is singular (a zero scale) or too large to invert, so the mesh it places cannot "
       "be animated"},
      {{}, [](json& d) { d["accessors"][0]["normalized"] = 1; }, "$.accessors[0].normalized: 1 is not true or false"},
  };
  for (size_t i = 0; i < std::size(cases); ++i) {
    SCOPED_TRACE(cases[i].message);
    const std::string name = "animation/bad/" + std::to_string(i) + ".gltf";
    const GltfBuilder b = animated_triangle(cases[i].change);
    EXPECT_EQ(error_loading(written(b.model, name, GltfForm::embedded, cases[i].patch)),
              name + ": " + cases[i].message);
  }
}

TEST(GltfAnimationErrors, SkinsAndMorphTargetsOfNonZeroWeightAreRefusedNotIgnored) {
  using nlohmann::json;
  const auto error_with = [](const std::function<void(json&)>& patch) {
    return error_loading(written(test::one_triangle().model, "animation/morph.gltf", GltfForm::embedded, patch));
  };
  const std::string at = "animation/morph.gltf: ";
  EXPECT_EQ(error_with([](json& d) {
              d["skins"] = {{{"joints", {0}}}};
              d["nodes"][0]["skin"] = 0;
            }),
            at + "$.nodes[0].skin: skinned meshes are not supported");
  EXPECT_EQ(error_with([](json& d) { d["nodes"][0]["skin"] = 2; }), at + "$.nodes[0].skin: 2 names no skin (0 skins)");
  const auto morph = [](json& d) { d["meshes"][0]["primitives"][0]["targets"] = {{{"POSITION", 0}}}; };
  EXPECT_EQ(error_with([&](json& d) {
              morph(d);
              d["meshes"][0]["weights"] = {0.5};
            }),
            at + "$.meshes[0].weights[0]: 0.5: morph targets of a non-zero weight are not supported");
  EXPECT_EQ(error_with([&](json& d) {
              morph(d);
              d["meshes"][0]["weights"] = {0};
              d["nodes"][0]["weights"] = {0.25};
            }),
            at + "$.nodes[0].weights[0]: 0.25: morph targets of a non-zero weight are not supported");
  EXPECT_EQ(error_with([&](json& d) { d["meshes"][0]["weights"] = {"a"}; }),
            at + "$.meshes[0].weights[0]: \"a\" is not a number");
  // Weights of 0 leave the mesh as it is: read without its targets. So do a node's zero
  // weights in place of its mesh's, and targets without weights (0 by default).
  EXPECT_EQ(error_with([&](json& d) {
              morph(d);
              d["meshes"][0]["weights"] = {0};
            }),
            "no error");
  EXPECT_EQ(error_with([&](json& d) {
              morph(d);
              d["meshes"][0]["weights"] = {0.5};
              d["nodes"][0]["weights"] = {0};
            }),
            "no error");
  EXPECT_EQ(error_with(morph), "no error");
}

}  // namespace
}  // namespace rp
