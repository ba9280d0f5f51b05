#pragma once
/// The mapping of a glTF model, as tinygltf read it, onto the Scene (what is mapped and how:
/// the top of io/loaders/gltf.cpp). Internal to the glTF loader, in three files by job:
/// gltf_scene.cpp walks the node hierarchy and places meshes (baked or instanced), cameras,
/// lights and materials; gltf_mesh.cpp reads accessors and turns primitives into triangles;
/// gltf_animation.cpp reads the animations into the curves of a SceneAnimation.

#include <array>
#include <cstdint>
#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

#include "base/error.h"
#include "core/scene.h"
#include "io/loaders/animation.h"
#include "io/loaders/tinygltf_config.h"

namespace rp {

using Matrix = Affine3d;

/// Every primitive of one glTF mesh as one TriangleMesh, and the nodes that place it.
struct MeshUse {
  std::vector<std::pair<Matrix, int>> placements;  ///< node-to-world, node index
};

/// Reads one tinygltf model into a Scene; every check names the file and the JSON path.
class GltfReader {
 public:
  GltfReader(const std::string& file, const tinygltf::Model& model, Scene& scene)
      : file_(file), m_(model), scene_(scene), materials_(model.materials.size(), kInvalidId) {}

  /// Maps the default scene (or the first) onto the Scene, then prints the warnings kept;
  /// returns the file's animation, whose targets are the Scene's instances, lights and camera.
  /// Throws rp::Error naming the file and the JSON path.
  SceneAnimation read();

 private:
  void read_scene();

  [[noreturn]] void fail(const std::string& path, const std::string& what) const {
    throw Error(cat(file_, ": ", path, ": ", what));
  }

  /// What check_gltf_json made true of the value at `path` (an index names an element, a
  /// value lies in glTF's range): the reader relies on it to stay in bounds, so a breach, a bug
  /// in raypack, is refused rather than read past.
  void guaranteed(bool holds, const std::string& path) const {
    RP_CHECK(holds, file_, ": ", path, ": not as the JSON check left it (a bug in raypack)");
  }

  /// Element i of section `v` of the model, the index at `path`.
  template <class T>
  const T& at(const std::vector<T>& v, int i, const std::string& path) const {
    guaranteed(i >= 0 && size_t(i) < v.size(), path);
    return v[size_t(i)];
  }

  /// A warning kept until the end of read(): the first of its kind (the same words at a path
  /// differing only in its indices) with how many more there were, so that 2,000 nodes with
  /// the same fault give one line, not 2,000.
  struct Warning {
    std::string path, what;
    size_t more = 0;
  };
  void warning(const std::string& path, const std::string& what);
  /// Prints the warnings kept, each once: "(and 1,599 more nodes like it)" after the first of a
  /// kind, the elements named as the last array of its path.
  void print_warnings();

  /// Extensions the file requires that change what its geometry is: refused, as the geometry
  /// would be wrong without them. Other required extensions (textures, materials) are warned
  /// about: raypack does not use what they change.
  void check_required_extensions();

  // ---- the node hierarchy ----

  struct Placed {
    int mesh, node;
    Matrix to_world;
  };

  /// Node n's own translation, rotation and scale (its numbers checked by check_gltf_json: as
  /// many as glTF says, finite, the rotation a unit quaternion within its tolerance).
  NodeTrs trs(int n) const;

  /// The local transform of node n: its matrix, or NodeTrs::matrix() of trs(n).
  Matrix local(int n) const;

  /// Walks scene s from its roots: every node once (a node met again is in a cycle or has two
  /// parents, which glTF forbids), depth-first without recursion. A node that the animation
  /// moves (animated, or below an animated node) is listed in moving_ as it is entered.
  void walk(int s);

  /// What node n places, at `to_world`; refuses a skin, and morph targets of non-zero weight.
  void visit(int n, const Matrix& to_world);

  /// The index of node n in moving_, or -1 when the animation does not move it.
  int moving(int n) const { return moving_index_[size_t(n)]; }

  /// Records what node n placed as a target of the animation, when the animation moves n: its
  /// kind, its index in the Scene, a light's power, the camera's model and field of view.
  void follow(int n, AnimatedTarget::Kind kind, uint32_t index, const Vec3f& power = Vec3f(1.0f),
              const CameraDesc& camera = {});

  // ---- animations (gltf_animation.cpp) ----

  /// Reads every animation's channels into curves_ and node_curves_ (each channel its own
  /// curve), refusing what cannot be sampled: morph-target weights, a node with a matrix, two
  /// channels on one node and property, and samplers whose accessors are not glTF's (their
  /// types, counts, times not finite or not increasing, values not finite, rotations that are
  /// not unit quaternions).
  void read_animations();

  /// The curve of sampler s of animation a, animating `property` for channel path `cp`.
  AnimationCurve curve(int a, int s, AnimatedProperty property, const std::string& cp) const;

  // ---- cameras and lights ----

  void camera(int n, const Matrix& to_world);

  /// The light `ext` (a node's KHR_lights_punctual object, its integer "light" and the light's
  /// type and color checked by check_gltf_json) names.
  void light(int n, const tinygltf::Value& ext, const Matrix& to_world);

  // ---- materials ----

  /// The scene's material for glTF material i (-1: the default grey), added on first use.
  uint32_t material(int i, const std::string& path);

  // ---- accessors ----

  /// An accessor's elements as raypack reads them: `count` elements `stride` bytes apart from
  /// `data`, each of `components` components of `component_type`.
  struct View {
    const unsigned char* data;
    size_t count, stride, components;
    int component_type;
  };

  /// Accessor a, which `use` reads as `type` (TINYGLTF_TYPE_SCALAR, VEC3 or VEC4) of one of
  /// `component_types`: every element inside its bufferView and buffer (checked in 64 bits
  /// before anything is read or allocated for it).
  View view(int a, const std::string& use, int type, std::initializer_list<int> component_types) const;

  std::vector<Vec3f> vectors(const View& v) const;

  std::vector<uint32_t> indices(const View& v) const;

  /// Every component of every element as a double: floats as they are, integers of a
  /// normalized accessor mapped to [-1, 1] or [0, 1] as glTF 2.0 says (signed: max(c / 127,
  /// -1), max(c / 32767, -1); unsigned: c / 255, c / 65535).
  std::vector<double> numbers(const View& v) const;

  // ---- meshes ----

  /// glTF mesh i's triangle primitives as one TriangleMesh in its own coordinates (no
  /// triangles: every primitive skipped).
  TriangleMesh convert(int i);

  /// The corners of a primitive of `mode` (4 triangles, 5 strip, 6 fan) as triangles.
  static std::vector<uint32_t> triangulate(const std::vector<uint32_t>& c, int mode);

  /// glTF mesh i where `use` places it: baked into world coordinates by one node, stored once
  /// and instanced by several, or by any node the animation moves (each such instance a
  /// target of the animation).
  void place_mesh(int i, const MeshUse& use);

  const std::string& file_;
  const tinygltf::Model& m_;
  Scene& scene_;
  std::vector<uint32_t> materials_;  ///< glTF material -> scene material (kInvalidId: not added yet)
  std::vector<Placed> placed_;
  bool camera_set_ = false;
  std::vector<Warning> warnings_;
  std::vector<AnimationCurve> curves_;
  std::vector<std::array<int, 3>> node_curves_;  ///< per glTF node: its curve per AnimatedProperty, or -1
  AnimationCounts counts_;
  std::vector<int> moving_index_;     ///< per glTF node: moving(n)
  std::vector<AnimatedNode> moving_;  ///< the nodes the animation moves, parents first
  std::vector<AnimatedTarget> targets_;
};

}  // namespace rp
