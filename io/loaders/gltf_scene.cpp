/// The glTF node hierarchy onto the Scene (io/loaders/gltf_reader.h): the scene's nodes
/// walked from its roots, each mesh baked by one node or instanced by several (or by a node
/// the animation moves), the first camera, KHR_lights_punctual lights, materials, what the
/// animation moves, and the warnings of one load.

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "base/error.h"
#include "base/text.h"
#include "io/loaders/gltf_check.h"
#include "io/loaders/gltf_reader.h"

namespace rp {
namespace {

/// Digits grouped by thousands: 1,599.
std::string grouped(uint64_t n) {
  const std::string digits = std::to_string(n);
  std::string out;
  for (size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return out;
}

/// The column-major 4x4 `m` as an affine map; nothing when its last row is not 0 0 0 1.
std::optional<Matrix> affine_of(const std::vector<double>& m) {
  if (m[3] != 0.0 || m[7] != 0.0 || m[11] != 0.0 || m[15] != 1.0) return std::nullopt;
  Matrix a;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) a.m[r][c] = m[size_t(c * 4 + r)];
  return a;
}

}  // namespace

SceneAnimation GltfReader::read() {
  try {
    read_scene();
  } catch (...) {
    print_warnings();
    throw;
  }
  print_warnings();
  return SceneAnimation(file_, std::move(curves_), std::move(moving_), std::move(targets_), counts_);
}

void GltfReader::read_scene() {
  check_required_extensions();
  if (m_.scenes.empty()) fail("$.scenes", "the file has no scene");
  read_animations();
  walk(m_.defaultScene >= 0 ? m_.defaultScene : 0);
  std::vector<MeshUse> uses(m_.meshes.size());
  for (const Placed& p : placed_) uses[size_t(p.mesh)].placements.emplace_back(p.to_world, p.node);
  for (size_t i = 0; i < uses.size(); ++i)
    if (!uses[i].placements.empty()) place_mesh(int(i), uses[i]);
}

void GltfReader::warning(const std::string& path, const std::string& what) {
  const auto kind = [](const std::string& p) {
    std::string k;
    for (char c : p)
      if (!std::isdigit(static_cast<unsigned char>(c))) k += c;
    return k;
  };
  for (Warning& w : warnings_)
    if (w.what == what && kind(w.path) == kind(path)) {
      ++w.more;
      return;
    }
  warnings_.push_back({path, what, 0});
}

void GltfReader::print_warnings() {
  for (const Warning& w : warnings_) {
    std::string more;
    if (w.more > 0) {
      // The elements are named by the path's last array: "$.nodes[7]" -> "nodes".
      const size_t open = w.path.rfind('[');
      size_t start = open == std::string::npos ? 0 : open;
      while (start > 0 && w.path[start - 1] != '.') --start;
      const std::string noun = open == std::string::npos ? std::string("elements") : w.path.substr(start, open - start);
      more = cat(" (and ", grouped(w.more), " more ", noun, " like it)");
    }
    warn(cat(file_, ": ", w.path, ": ", w.what, more));
  }
  warnings_.clear();
}

void GltfReader::check_required_extensions() {
  static constexpr std::string_view kGeometry[] = {"KHR_draco_mesh_compression", "EXT_meshopt_compression",
                                                   "KHR_mesh_quantization", "EXT_mesh_gpu_instancing"};
  static constexpr std::string_view kUsed[] = {"KHR_lights_punctual", "KHR_materials_emissive_strength"};
  for (size_t i = 0; i < m_.extensionsRequired.size(); ++i) {
    const std::string& e = m_.extensionsRequired[i];
    const std::string path = cat("$.extensionsRequired[", i, "]");
    if (std::find(std::begin(kGeometry), std::end(kGeometry), e) != std::end(kGeometry))
      fail(path, cat(gltf_quoted(e), " is not supported (its geometry cannot be read without it)"));
    if (std::find(std::begin(kUsed), std::end(kUsed), e) == std::end(kUsed))
      warning(path, cat(gltf_quoted(e), " is not supported; what it changes is not used"));
  }
}

NodeTrs GltfReader::trs(int n) const {
  const tinygltf::Node& node = m_.nodes[size_t(n)];
  NodeTrs out;
  const auto take = [](const std::vector<double>& v, auto& to) {
    if (v.size() == to.size()) std::copy(v.begin(), v.end(), to.begin());
  };
  take(node.translation, out.translation);
  take(node.rotation, out.rotation);
  take(node.scale, out.scale);
  return out;
}

Matrix GltfReader::local(int n) const {
  const tinygltf::Node& node = m_.nodes[size_t(n)];
  if (!node.matrix.empty()) {
    const std::optional<Matrix> a = affine_of(node.matrix);
    if (!a) fail(cat("$.nodes[", n, "].matrix"), "not an affine transform (its last row is not 0 0 0 1)");
    return *a;
  }
  return trs(n).matrix();
}

void GltfReader::walk(int s) {
  const tinygltf::Scene& scene = at(m_.scenes, s, "$.scene");
  std::vector<uint8_t> state(m_.nodes.size(), 0);  // 0 unseen, 1 on the current path, 2 done
  moving_index_.assign(m_.nodes.size(), -1);
  struct Frame {
    int node;
    Matrix to_world;
    size_t next_child;
  };
  std::vector<Frame> stack;
  const auto enter = [&](int n, const Matrix& parent, int parent_moving, const std::string& path) {
    at(m_.nodes, n, path);
    if (state[size_t(n)] == 1) fail(path, cat("node ", n, " is its own ancestor (a cycle)"));
    if (state[size_t(n)] == 2) fail(path, cat("node ", n, " is reached twice (a node may have one parent only)"));
    state[size_t(n)] = 1;
    const Matrix own = local(n);
    AnimatedNode a;
    a.curves = node_curves_[size_t(n)];
    if (parent_moving >= 0 || a.animated()) {
      a.path = cat("$.nodes[", n, "]");
      a.parent = parent_moving;
      if (parent_moving < 0) a.base = parent;
      a.rest = trs(n);
      a.local = own;
      moving_index_[size_t(n)] = int(moving_.size());
      moving_.push_back(std::move(a));
    }
    const Matrix to_world = compose(parent, own);
    visit(n, to_world);
    stack.push_back({n, to_world, 0});
  };
  for (size_t r = 0; r < scene.nodes.size(); ++r) {
    enter(scene.nodes[r], Matrix{}, -1, cat("$.scenes[", s, "].nodes[", r, "]"));
    while (!stack.empty()) {
      Frame& f = stack.back();
      const tinygltf::Node& node = m_.nodes[size_t(f.node)];
      if (f.next_child == node.children.size()) {
        state[size_t(f.node)] = 2;
        stack.pop_back();
        continue;
      }
      const size_t c = f.next_child++;
      const Matrix parent = f.to_world;
      enter(node.children[c], parent, moving(f.node), cat("$.nodes[", f.node, "].children[", c, "]"));
    }
  }
}

void GltfReader::visit(int n, const Matrix& to_world) {
  const tinygltf::Node& node = m_.nodes[size_t(n)];
  const std::string path = cat("$.nodes[", n, "]");
  if (node.skin >= 0) fail(path + ".skin", "skinned meshes are not supported");
  if (node.mesh >= 0) {
    const tinygltf::Mesh& mesh = at(m_.meshes, node.mesh, path + ".mesh");
    // Morph targets are not read: refused unless their weights leave the mesh as it is.
    const bool targets = std::any_of(mesh.primitives.begin(), mesh.primitives.end(),
                                     [](const tinygltf::Primitive& p) { return !p.targets.empty(); });
    const bool own = !node.weights.empty();
    const std::vector<double>& weights = own ? node.weights : mesh.weights;
    for (size_t k = 0; targets && k < weights.size(); ++k)
      if (weights[k] != 0.0)
        fail(cat(own ? path : cat("$.meshes[", node.mesh, "]"), ".weights[", k, "]"),
             cat(weights[k], ": morph targets of a non-zero weight are not supported"));
    placed_.push_back({node.mesh, n, to_world});
  }
  if (node.camera >= 0) camera(n, to_world);
  if (const auto it = node.extensions.find("KHR_lights_punctual"); it != node.extensions.end())
    light(n, it->second, to_world);
}

void GltfReader::camera(int n, const Matrix& to_world) {
  if (camera_set_) return;  // the first one met
  const tinygltf::Node& node = m_.nodes[size_t(n)];
  const tinygltf::Camera& c = at(m_.cameras, node.camera, cat("$.nodes[", n, "].camera"));
  const std::string cp = cat("$.cameras[", node.camera, "]");
  if (c.type != "perspective") {
    warning(cp, cat("a ", gltf_quoted(c.type), " camera is not supported; it is not used"));
    return;
  }
  CameraDesc d;
  d.vfov_degrees = float(c.perspective.yfov * 180.0 / kPi);
  const std::optional<CameraDesc> placed = node_camera(to_world, d);
  if (!placed) {
    warning(cp, "its field of view or its node's placement cannot make a camera; it is not used");
    return;
  }
  scene_.set_camera(*placed);
  camera_set_ = true;
  follow(n, AnimatedTarget::Kind::camera, 0, Vec3f(1.0f), d);
}

void GltfReader::follow(int n, AnimatedTarget::Kind kind, uint32_t index, const Vec3f& power,
                        const CameraDesc& camera) {
  if (moving(n) < 0) return;
  AnimatedTarget t;
  t.kind = kind;
  t.node = uint32_t(moving(n));
  t.index = index;
  t.power = power;
  t.camera = camera;
  targets_.push_back(t);
}

void GltfReader::light(int n, const tinygltf::Value& ext, const Matrix& to_world) {
  const int l = ext.Get("light").GetNumberAsInt();
  const tinygltf::Light& light = at(m_.lights, l, cat("$.nodes[", n, "].extensions.KHR_lights_punctual.light"));
  const std::string lp = cat("$.extensions.KHR_lights_punctual.lights[", l, "]");
  Vec3d colour(1.0);
  if (light.color.size() == 3) colour = {light.color[0], light.color[1], light.color[2]};
  const Vec3f power = Vec3f(colour * light.intensity);
  const bool directional = light.type == "directional";
  try {
    if (directional) {
      scene_.add_light(node_directional_light(to_world, power));
    } else {
      if (light.type == "spot") warning(lp, "a \"spot\" light is placed as a point light");
      scene_.add_light(node_point_light(to_world, power));
    }
  } catch (const Error& e) {
    fail(lp, e.what());
  }
  if (directional)
    follow(n, AnimatedTarget::Kind::directional_light, uint32_t(scene_.directional_lights().size() - 1), power);
  else
    follow(n, AnimatedTarget::Kind::point_light, uint32_t(scene_.point_lights().size() - 1), power);
}

uint32_t GltfReader::material(int i, const std::string& path) {
  if (i < 0) return 0;
  const tinygltf::Material& g = at(m_.materials, i, path);
  uint32_t& id = materials_[size_t(i)];
  if (id != kInvalidId) return id;
  const std::string mp = cat("$.materials[", i, "]");
  const std::vector<double>& base = g.pbrMetallicRoughness.baseColorFactor;
  Material m;
  m.name = g.name.empty() ? cat("material ", i) : g.name;
  if (base.size() == 4) {
    m.diffuse = Vec3f(float(base[0]), float(base[1]), float(base[2]));
    if (g.alphaMode == "BLEND") m.opacity = float(base[3]);
  }
  if (g.emissiveFactor.size() == 3) {
    double strength = 1.0;
    if (const auto it = g.extensions.find("KHR_materials_emissive_strength");
        it != g.extensions.end() && it->second.Has("emissiveStrength"))
      strength = it->second.Get("emissiveStrength").GetNumberAsDouble();
    m.emission = Vec3f(Vec3d(g.emissiveFactor[0], g.emissiveFactor[1], g.emissiveFactor[2]) * strength);
  }
  const auto bad = [](const Vec3f& v) { return !is_finite(v) || min_component(v) < 0.0f; };
  if (bad(m.diffuse) || bad(m.emission) || !(m.opacity >= 0.0f && m.opacity <= 1.0f))
    fail(mp, "its base colour, alpha or emission is negative or not a finite number");
  id = scene_.add_material(std::move(m));
  return id;
}

void GltfReader::place_mesh(int i, const MeshUse& use) {
  TriangleMesh mesh = convert(i);
  if (mesh.indices.empty()) return;
  const std::string mp = cat("$.meshes[", i, "]");
  std::vector<std::pair<Matrix, int>> placements;
  bool moves = false;
  for (const auto& [to_world, node] : use.placements) {
    if (!inverse(to_world)) {
      // A mesh the animation moves could not be placed at the poses it reaches from here.
      if (moving(node) >= 0)
        fail(cat("$.nodes[", node, "]"),
             "its rest transform is singular (a zero scale) or too large to invert, so the mesh it places cannot be "
             "animated");
      warning(cat("$.nodes[", node, "]"),
              "its transform is singular (a zero scale) or too large to invert; its mesh is not placed");
      continue;
    }
    moves = moves || moving(node) >= 0;
    placements.emplace_back(to_world, node);
  }
  if (placements.empty()) return;
  if (placements.size() == 1 && !moves) {
    const Matrix& t = placements[0].first;
    const Matrix w = *inverse(t);
    for (Vec3f& p : mesh.positions) p = Vec3f(t.point(Vec3d(p)));
    for (Vec3f& n : mesh.normals) n = Vec3f(normalize(w.transpose_vector(Vec3d(n))));
    try {
      scene_.add_mesh(std::move(mesh));
    } catch (const Error& e) {
      fail(cat("$.nodes[", placements[0].second, "]"), e.what());
    }
    return;
  }
  uint32_t id = 0;
  try {
    id = scene_.add_instanced_mesh(std::move(mesh));
  } catch (const Error& e) {
    fail(mp, e.what());
  }
  for (const auto& [to_world, node] : placements) {
    uint32_t instance = 0;
    try {
      instance = scene_.add_instance(id, Affine3f(to_world));
    } catch (const Error& e) {
      fail(cat("$.nodes[", node, "]"), e.what());
    }
    follow(node, AnimatedTarget::Kind::instance, instance);
  }
}

}  // namespace rp
