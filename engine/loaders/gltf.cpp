/// glTF 2.0 scenes (.gltf with external or data-URI buffers, .glb) through tinygltf 2.7
/// (engine/loaders/tinygltf_impl.cpp), mapped onto the Scene:
///
/// - the default scene (`scene`), or the first when there is none; its node hierarchy walked
///   from its roots, each node's transform its `matrix` (column-major, which must be affine)
///   or T * R * S from `translation`, `rotation` (a unit quaternion x, y, z, w; normalised on
///   reading) and `scale`, composed parent * child in double;
/// - meshes: every triangle primitive (mode 4, and strips 5 and fans 6 turned into triangles;
///   indexed or not, indices of any unsigned type) of a glTF mesh becomes part of one
///   TriangleMesh, a primitive's material on its triangles; NORMAL kept when every primitive of
///   the mesh has it. A mesh one node places is baked into world coordinates; a mesh several
///   nodes place is stored once in its own coordinates and each node is an instance
///   (Scene::add_instance);
/// - the first camera met in that walk, when perspective: eye, look-at one unit down its -Z,
///   up its +Y, `yfov` as the vertical field of view (the image's aspect replaces
///   `aspectRatio`; `znear`, `zfar` are not used);
/// - KHR_lights_punctual lights placed by nodes: "point" (intensity in candela: color *
///   intensity / r^2 is the irradiance, as raypack's PointLight), "directional" (along the
///   node's -Z, color * intensity as irradiance, lux); "spot" as a point light, with a warning;
///   `range` is not used. No exposure is applied: a file's physical intensities are the
///   renderer's;
/// - materials: baseColorFactor's rgb to diffuse, emissiveFactor (times
///   KHR_materials_emissive_strength) to emission, baseColorFactor's alpha to opacity when
///   alphaMode is "BLEND". Not used: textures of every kind, metallic and roughness, normal and
///   occlusion maps, alpha masks, doubleSided (raypack's surfaces are seen from both sides),
///   every other material extension; images are neither decoded nor opened.
///
/// Refused with one line naming the file and the JSON path: sparse accessors, Draco-compressed
/// primitives without an uncompressed fallback, accessors whose elements do not fit their
/// bufferView and buffer (bad offsets, strides, absurd counts: checked before anything is
/// allocated for them), indices out of range, positions that are not 3 floats or lie outside
/// the coordinate range, node cycles and nodes with two parents, non-affine matrices, missing
/// or unreadable buffers (a device, a directory: engine/input_file.h's rule), required
/// extensions that change geometry (Draco, meshopt, mesh quantization, GPU instancing), and
/// whatever tinygltf refuses (its first line). Warned about and skipped: points and lines,
/// primitives without positions, nodes whose transform is singular, a camera or light that
/// cannot be used. Size limits: the file itself and each external buffer at most kMaxGltfBytes
/// (a .glb below 4 GiB, tinygltf's own limit), JSON nested at most 64 levels (checked before
/// parsing, as every JSON reader of raypack).

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <unistd.h>

#include "engine/error.h"
#include "engine/input_file.h"
#include "engine/json_text.h"
#include "engine/loaders/load.h"
#include "engine/loaders/tinygltf_config.h"
#include "engine/text.h"

namespace rp {
namespace {

/// The most bytes of a glTF file, and of each external buffer it names: 2 GiB.
constexpr uint64_t kMaxGltfBytes = uint64_t(2) << 30;

/// A string from the file, quoted (cut and made printable by rp::printable).
std::string in_quotes(std::string_view text) { return cat("\"", printable(text), "\""); }

/// What the file-system callbacks give tinygltf: the glTF file's folder, and the first
/// failure, so that it can be reported with the buffer's JSON path.
struct FileAccess {
  std::string base_dir;  ///< with a trailing '/', or empty for the current folder
  std::string failed_path;
  std::string failure;
};

/// tinygltf asks whether a candidate path exists before reading it (the glTF's folder joined
/// with the URI, then "./" joined with it): only the first is raypack's answer, so a buffer is
/// never looked for in the current folder; ReadWholeFile opens it and says what is wrong.
bool file_exists(const std::string& path, void* user) {
  const FileAccess& a = *static_cast<const FileAccess*>(user);
  return a.base_dir.empty() ? true : path.rfind(a.base_dir, 0) == 0;
}

/// No expansion (tinygltf's own runs wordexp on the path).
std::string expand_path(const std::string& path, void*) { return path; }

/// Reads an external buffer by raypack's input rule: a regular file (not a device, FIFO or
/// directory) of at most kMaxGltfBytes, its size known before anything is allocated.
bool read_whole_file(std::vector<unsigned char>* out, std::string* err, const std::string& path, void* user) {
  FileAccess& a = *static_cast<FileAccess*>(user);
  try {
    uint64_t size = 0;
    const int fd = open_regular_file(path, size);
    ::close(fd);
    if (size > kMaxGltfBytes) throw Error(cat(path, ": ", size, " bytes, more than the ", kMaxGltfBytes, " a buffer may have"));
    const std::string bytes = read_file(path);
    out->assign(bytes.begin(), bytes.end());
    return true;
  } catch (const Error& e) {
    if (a.failure.empty()) {
      a.failed_path = path;
      a.failure = e.what();
    }
    if (err) *err += e.what();
    return false;
  }
}

bool write_whole_file(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
  if (err) *err += "raypack writes no files while reading a glTF";
  return false;
}

/// Images are not decoded: accepted as they are and never used.
bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) {
  return true;
}

/// The JSON text of a GLB (its first chunk), after checking the 12-byte header and every chunk
/// against the file's size: each chunk's 8-byte header and the length it claims inside the
/// file, the second chunk (when there is one) BIN, the last ending where the file does.
/// tinygltf 2.7 checks the BIN chunk's length without its header and would copy up to 8 bytes
/// past the file. Throws one line naming the file for a truncated or malformed one.
std::string_view glb_json(const std::string& path, std::string_view bytes) {
  const auto u32 = [&](size_t at) {
    uint32_t v;
    std::memcpy(&v, bytes.data() + at, 4);
    return v;
  };
  if (bytes.size() < 20)
    throw Error(cat(path, ": truncated GLB: ", bytes.size(), " bytes, its headers need 20"));
  if (u32(4) != 2) throw Error(cat(path, ": GLB version ", u32(4), " (2 is read)"));
  if (u32(8) != bytes.size())
    throw Error(cat(path, ": ", u32(8) < bytes.size() ? "GLB with trailing bytes" : "truncated GLB", ": the header says ",
                    u32(8), " bytes, the file has ", bytes.size()));
  const uint64_t json_bytes = u32(12);
  if (u32(16) != 0x4E4F534Au) throw Error(cat(path, ": GLB whose first chunk is not JSON"));
  if (20 + json_bytes > bytes.size())
    throw Error(cat(path, ": truncated GLB: its JSON chunk says ", json_bytes, " bytes, ", bytes.size() - 20, " follow"));
  for (uint64_t at = 20 + json_bytes; at < bytes.size();) {
    const uint64_t left = bytes.size() - at;
    if (left < 8)
      throw Error(cat(path, ": truncated GLB: the chunk at byte ", at, " has ", left, " of its 8 header bytes"));
    const bool second = at == 20 + json_bytes;
    if (second && u32(at + 4) != 0x004E4942u)
      throw Error(cat(path, ": GLB whose second chunk is of type ", in_quotes(bytes.substr(at + 4, 4)), ", not BIN"));
    const uint64_t length = u32(at);
    if (length > left - 8)
      throw Error(cat(path, ": truncated GLB: its ", second ? std::string("BIN chunk") : cat("chunk at byte ", at),
                      " says ", length, " bytes, ", left - 8, " follow"));
    at += 8 + length;
  }
  return bytes.substr(20, size_t(json_bytes));
}

/// `uri` with its %XX escapes decoded, as tinygltf decodes a buffer's URI before opening it.
std::string percent_decoded(const std::string& uri) {
  std::string out;
  for (size_t i = 0; i < uri.size(); ++i) {
    const auto hex = [&](size_t k) { return k < uri.size() && std::isxdigit(static_cast<unsigned char>(uri[k])); };
    if (uri[i] == '%' && hex(i + 1) && hex(i + 2)) {
      out += char(std::stoi(uri.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      out += uri[i];
    }
  }
  return out;
}

/// "$.buffers[i].uri" for the external buffer whose file is `file` (found in the JSON text by
/// its URI, for the message of a buffer that could not be read), or "$.buffers".
std::string buffer_path(std::string_view json, const std::string& base_dir, const std::string& file) {
  const nlohmann::json doc = nlohmann::json::parse(json.begin(), json.end(), nullptr, false);
  if (doc.is_object() && doc.contains("buffers") && doc["buffers"].is_array()) {
    const nlohmann::json& buffers = doc["buffers"];
    for (size_t i = 0; i < buffers.size(); ++i)
      if (buffers[i].is_object() && buffers[i].contains("uri") && buffers[i]["uri"].is_string()) {
        const std::string uri = buffers[i]["uri"].get<std::string>();
        if (file == base_dir + uri || file == base_dir + percent_decoded(uri))
          return cat("$.buffers[", i, "].uri: ", in_quotes(uri));
      }
  }
  return "$.buffers";
}

/// The first line of a message tinygltf built of several.
std::string first_line(const std::string& s) {
  std::string line = s.substr(0, s.find('\n'));
  while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '.')) line.pop_back();
  return line.empty() ? std::string("tinygltf refused it") : one_line(line);
}

using Matrix = Affine3d;

/// The column-major 4x4 `m` as an affine map; nothing when its last row is not 0 0 0 1.
std::optional<Matrix> affine_of(const std::vector<double>& m) {
  if (m[3] != 0.0 || m[7] != 0.0 || m[11] != 0.0 || m[15] != 1.0) return std::nullopt;
  Matrix a;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) a.m[r][c] = m[size_t(c * 4 + r)];
  return a;
}

/// T * R * S of translation t, unit quaternion q (x, y, z, w) and scale s.
Matrix trs(const std::array<double, 3>& t, const std::array<double, 4>& q, const std::array<double, 3>& s) {
  const double x = q[0], y = q[1], z = q[2], w = q[3];
  const double r[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)},
                          {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)},
                          {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)}};
  Matrix a;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) a.m[i][j] = r[i][j] * s[size_t(j)];
    a.m[i][3] = t[size_t(i)];
  }
  return a;
}

/// Every primitive of one glTF mesh as one TriangleMesh, and the nodes that place it.
struct MeshUse {
  std::vector<std::pair<Matrix, int>> placements;  ///< node-to-world, node index
};

class GltfReader {
 public:
  GltfReader(const std::string& file, const tinygltf::Model& model, Scene& scene)
      : file_(file), m_(model), scene_(scene), materials_(model.materials.size(), kInvalidId) {}

  void read() {
    check_required_extensions();
    if (m_.scenes.empty()) fail("$.scenes", "the file has no scene");
    const int s = m_.defaultScene >= 0 ? m_.defaultScene : 0;
    if (size_t(s) >= m_.scenes.size()) fail("$.scene", cat(s, " names no scene (", m_.scenes.size(), " scenes)"));
    walk(s);
    std::vector<MeshUse> uses(m_.meshes.size());
    for (const Placed& p : placed_) uses[size_t(p.mesh)].placements.emplace_back(p.to_world, p.node);
    for (size_t i = 0; i < uses.size(); ++i)
      if (!uses[i].placements.empty()) place_mesh(int(i), uses[i]);
  }

 private:
  [[noreturn]] void fail(const std::string& path, const std::string& what) const {
    throw Error(cat(file_, ": ", path, ": ", what));
  }
  void warning(const std::string& path, const std::string& what) const { warn(cat(file_, ": ", path, ": ", what)); }

  /// Extensions the file requires that change what its geometry is: refused, as the geometry
  /// would be wrong without them. Other required extensions (textures, materials) are warned
  /// about: raypack does not use what they change.
  void check_required_extensions() const {
    static constexpr std::string_view kGeometry[] = {"KHR_draco_mesh_compression", "EXT_meshopt_compression",
                                                     "KHR_mesh_quantization", "EXT_mesh_gpu_instancing"};
    static constexpr std::string_view kUsed[] = {"KHR_lights_punctual", "KHR_materials_emissive_strength"};
    for (size_t i = 0; i < m_.extensionsRequired.size(); ++i) {
      const std::string& e = m_.extensionsRequired[i];
      const std::string path = cat("$.extensionsRequired[", i, "]");
      if (std::find(std::begin(kGeometry), std::end(kGeometry), e) != std::end(kGeometry))
        fail(path, cat(in_quotes(e), " is not supported (its geometry cannot be read without it)"));
      if (std::find(std::begin(kUsed), std::end(kUsed), e) == std::end(kUsed))
        warning(path, cat(in_quotes(e), " is not supported; what it changes is not used"));
    }
  }

  // ---- the node hierarchy ----

  struct Placed {
    int mesh, node;
    Matrix to_world;
  };

  /// The local transform of node n.
  Matrix local(int n) const {
    const tinygltf::Node& node = m_.nodes[size_t(n)];
    const std::string path = cat("$.nodes[", n, "]");
    const auto finite = [&](const std::vector<double>& v, const char* key) {
      for (double x : v)
        if (!std::isfinite(x)) fail(cat(path, ".", key), "holds a value that is not a finite number");
    };
    if (!node.matrix.empty()) {
      if (node.matrix.size() != 16) fail(path + ".matrix", cat(node.matrix.size(), " numbers, not 16"));
      finite(node.matrix, "matrix");
      const std::optional<Matrix> a = affine_of(node.matrix);
      if (!a) fail(path + ".matrix", "not an affine transform (its last row is not 0 0 0 1)");
      return *a;
    }
    std::array<double, 3> t{0, 0, 0}, s{1, 1, 1};
    std::array<double, 4> q{0, 0, 0, 1};
    const auto take = [&](const std::vector<double>& v, const char* key, auto& out) {
      if (v.empty()) return;
      if (v.size() != out.size()) fail(cat(path, ".", key), cat(v.size(), " numbers, not ", out.size()));
      finite(v, key);
      std::copy(v.begin(), v.end(), out.begin());
    };
    take(node.translation, "translation", t);
    take(node.rotation, "rotation", q);
    take(node.scale, "scale", s);
    const double len = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (!(len > 0.0)) fail(path + ".rotation", "a zero quaternion is no rotation");
    for (double& c : q) c /= len;
    return trs(t, q, s);
  }

  /// Walks scene s from its roots: every node once (a node met again is in a cycle or has two
  /// parents, which glTF forbids), depth-first without recursion.
  void walk(int s) {
    const tinygltf::Scene& scene = m_.scenes[size_t(s)];
    std::vector<uint8_t> state(m_.nodes.size(), 0);  // 0 unseen, 1 on the current path, 2 done
    struct Frame {
      int node;
      Matrix to_world;
      size_t next_child;
    };
    std::vector<Frame> stack;
    const auto enter = [&](int n, const Matrix& parent, const std::string& path) {
      if (n < 0 || size_t(n) >= m_.nodes.size()) fail(path, cat(n, " names no node (", m_.nodes.size(), " nodes)"));
      if (state[size_t(n)] == 1) fail(path, cat("node ", n, " is its own ancestor (a cycle)"));
      if (state[size_t(n)] == 2) fail(path, cat("node ", n, " is reached twice (a node may have one parent only)"));
      state[size_t(n)] = 1;
      const Matrix to_world = compose(parent, local(n));
      visit(n, to_world);
      stack.push_back({n, to_world, 0});
    };
    for (size_t r = 0; r < scene.nodes.size(); ++r) {
      enter(scene.nodes[r], Matrix{}, cat("$.scenes[", s, "].nodes[", r, "]"));
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
        enter(node.children[c], parent, cat("$.nodes[", f.node, "].children[", c, "]"));
      }
    }
  }

  /// What node n places, at `to_world`.
  void visit(int n, const Matrix& to_world) {
    const tinygltf::Node& node = m_.nodes[size_t(n)];
    const std::string path = cat("$.nodes[", n, "]");
    if (node.mesh >= 0) {
      if (size_t(node.mesh) >= m_.meshes.size())
        fail(path + ".mesh", cat(node.mesh, " names no mesh (", m_.meshes.size(), " meshes)"));
      placed_.push_back({node.mesh, n, to_world});
    }
    if (node.camera >= 0) camera(n, to_world);
    if (const auto it = node.extensions.find("KHR_lights_punctual"); it != node.extensions.end()) light(n, it->second, to_world);
  }

  // ---- cameras and lights ----

  void camera(int n, const Matrix& to_world) {
    const tinygltf::Node& node = m_.nodes[size_t(n)];
    const std::string path = cat("$.nodes[", n, "].camera");
    if (size_t(node.camera) >= m_.cameras.size()) fail(path, cat(node.camera, " names no camera (", m_.cameras.size(), " cameras)"));
    if (camera_set_) return;  // the first one met
    const tinygltf::Camera& c = m_.cameras[size_t(node.camera)];
    const std::string cp = cat("$.cameras[", node.camera, "]");
    if (c.type != "perspective") {
      warning(cp, cat("a ", in_quotes(c.type), " camera is not supported; it is not used"));
      return;
    }
    const double fov = c.perspective.yfov * 180.0 / kPi;
    CameraDesc d;
    d.eye = Vec3f(to_world.point({0, 0, 0}));
    d.look_at = Vec3f(to_world.point({0, 0, -1}));
    d.up = Vec3f(to_world.vector({0, 1, 0}));
    d.vfov_degrees = float(fov);
    const Vec3f view = d.look_at - d.eye;
    if (!(fov > 0.0 && fov < 180.0) || !in_coordinate_range(d.eye) || !in_coordinate_range(d.look_at) ||
        !(length(view) > 0.0f) || !(length(cross(normalize(view), d.up)) > 1e-6f * length(d.up))) {
      warning(cp, "its field of view or its node's placement cannot make a camera; it is not used");
      return;
    }
    scene_.set_camera(d);
    camera_set_ = true;
  }

  void light(int n, const tinygltf::Value& ext, const Matrix& to_world) {
    const std::string path = cat("$.nodes[", n, "].extensions.KHR_lights_punctual");
    if (!ext.IsObject() || !ext.Has("light") || !ext.Get("light").IsInt())
      fail(path, "expected an object with an integer \"light\"");
    const int l = ext.Get("light").GetNumberAsInt();
    if (l < 0 || size_t(l) >= m_.lights.size()) fail(path + ".light", cat(l, " names no light (", m_.lights.size(), " lights)"));
    const tinygltf::Light& light = m_.lights[size_t(l)];
    const std::string lp = cat("$.extensions.KHR_lights_punctual.lights[", l, "]");
    Vec3d colour(1.0);
    if (!light.color.empty()) {
      if (light.color.size() != 3) fail(lp + ".color", cat(light.color.size(), " numbers, not 3"));
      colour = {light.color[0], light.color[1], light.color[2]};
    }
    const Vec3f power = Vec3f(colour * light.intensity);
    // The extension's three types; any other is a broken file, not a light to guess at.
    if (light.type != "directional" && light.type != "point" && light.type != "spot")
      fail(lp + ".type", cat(in_quotes(light.type), " is not a KHR_lights_punctual type (directional, point, spot)"));
    try {
      if (light.type == "directional") {
        scene_.add_light(DirectionalLight{Vec3f(normalize(to_world.vector({0, 0, -1}))), power});
      } else {
        if (light.type == "spot") warning(lp, "a \"spot\" light is placed as a point light");
        scene_.add_light(PointLight{Vec3f(to_world.point({0, 0, 0})), power});
      }
    } catch (const Error& e) {
      fail(lp, e.what());
    }
  }

  // ---- materials ----

  /// The scene's material for glTF material i (-1: the default grey), added on first use.
  uint32_t material(int i, const std::string& path) {
    if (i < 0) return 0;
    if (size_t(i) >= m_.materials.size()) fail(path, cat(i, " names no material (", m_.materials.size(), " materials)"));
    uint32_t& id = materials_[size_t(i)];
    if (id != kInvalidId) return id;
    const tinygltf::Material& g = m_.materials[size_t(i)];
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
      if (const auto it = g.extensions.find("KHR_materials_emissive_strength"); it != g.extensions.end() &&
                                                                                it->second.Has("emissiveStrength"))
        strength = it->second.Get("emissiveStrength").GetNumberAsDouble();
      m.emission = Vec3f(Vec3d(g.emissiveFactor[0], g.emissiveFactor[1], g.emissiveFactor[2]) * strength);
    }
    const auto bad = [](const Vec3f& v) { return !is_finite(v) || min_component(v) < 0.0f; };
    if (bad(m.diffuse) || bad(m.emission) || !(m.opacity >= 0.0f && m.opacity <= 1.0f))
      fail(mp, "its base colour, alpha or emission is negative or not a finite number");
    id = scene_.add_material(std::move(m));
    return id;
  }

  // ---- accessors ----

  /// An accessor's elements as raypack reads them: `count` elements `stride` bytes apart from
  /// `data`, each of `components` components of `component_type`.
  struct View {
    const unsigned char* data;
    size_t count, stride;
    int component_type;
  };

  /// Accessor a, which `use` reads as `type` (a TINYGLTF_TYPE_) of one of `component_types`:
  /// every element inside its bufferView and buffer (checked in 64 bits before anything is
  /// read or allocated for it).
  View view(int a, const std::string& use, int type, std::initializer_list<int> component_types) const {
    if (a < 0 || size_t(a) >= m_.accessors.size()) fail(use, cat(a, " names no accessor (", m_.accessors.size(), " accessors)"));
    const tinygltf::Accessor& acc = m_.accessors[size_t(a)];
    const std::string ap = cat("$.accessors[", a, "]");
    if (acc.sparse.isSparse) fail(ap + ".sparse", "sparse accessors are not supported");
    if (acc.type != type)
      fail(ap + ".type", cat(use, " needs ", type == TINYGLTF_TYPE_SCALAR ? "SCALAR" : "VEC3", " elements"));
    if (std::find(component_types.begin(), component_types.end(), acc.componentType) == component_types.end())
      fail(ap + ".componentType", cat(acc.componentType, " is not a component type ", use, " can have"));
    if (acc.bufferView < 0) fail(ap, "has no bufferView (all zeros, or data in an extension): not supported");
    if (size_t(acc.bufferView) >= m_.bufferViews.size())
      fail(ap + ".bufferView", cat(acc.bufferView, " names no bufferView (", m_.bufferViews.size(), " bufferViews)"));
    const tinygltf::BufferView& bv = m_.bufferViews[size_t(acc.bufferView)];
    const std::string vp = cat("$.bufferViews[", acc.bufferView, "]");
    if (bv.buffer < 0 || size_t(bv.buffer) >= m_.buffers.size())
      fail(vp + ".buffer", cat(bv.buffer, " names no buffer (", m_.buffers.size(), " buffers)"));
    const uint64_t buffer_bytes = m_.buffers[size_t(bv.buffer)].data.size();
    if (uint64_t(bv.byteOffset) > buffer_bytes || uint64_t(bv.byteLength) > buffer_bytes - bv.byteOffset)
      fail(vp, cat(bv.byteLength, " bytes from byte ", bv.byteOffset, " do not fit in buffer ", bv.buffer, "'s ",
                   buffer_bytes, " bytes"));
    const uint64_t components = type == TINYGLTF_TYPE_SCALAR ? 1 : 3;
    const uint64_t element = components * uint64_t(tinygltf::GetComponentSizeInBytes(uint32_t(acc.componentType)));
    const uint64_t stride = bv.byteStride == 0 ? element : bv.byteStride;
    if (stride < element || stride > 252)
      fail(vp + ".byteStride", cat(bv.byteStride, " is outside [", element, ", 252] for ", element, "-byte elements"));
    if (acc.count == 0) fail(ap + ".count", "0 elements");
    const uint64_t count = acc.count, offset = acc.byteOffset;
    // The last element ends at offset + (count - 1) * stride + element: no product overflows,
    // count being checked against the bytes first.
    if (offset > bv.byteLength || count - 1 > (bv.byteLength - offset) / stride ||
        offset + (count - 1) * stride + element > bv.byteLength)
      fail(ap, cat(count, " elements of ", element, " bytes, ", stride, " apart from byte ", offset, ", do not fit in ",
                   vp.substr(2), "'s ", bv.byteLength, " bytes"));
    return {m_.buffers[size_t(bv.buffer)].data.data() + bv.byteOffset + offset, size_t(count), size_t(stride),
            acc.componentType};
  }

  std::vector<Vec3f> vectors(const View& v) const {
    std::vector<Vec3f> out(v.count);
    for (size_t i = 0; i < v.count; ++i) std::memcpy(&out[i], v.data + i * v.stride, 12);
    return out;
  }

  std::vector<uint32_t> indices(const View& v) const {
    std::vector<uint32_t> out(v.count);
    for (size_t i = 0; i < v.count; ++i) {
      const unsigned char* p = v.data + i * v.stride;
      if (v.component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE) {
        out[i] = *p;
      } else if (v.component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT) {
        uint16_t s;
        std::memcpy(&s, p, 2);
        out[i] = s;
      } else {
        std::memcpy(&out[i], p, 4);
      }
    }
    return out;
  }

  // ---- meshes ----

  /// glTF mesh i's triangle primitives as one TriangleMesh in its own coordinates (no
  /// triangles: every primitive skipped).
  TriangleMesh convert(int i) {
    const tinygltf::Mesh& g = m_.meshes[size_t(i)];
    TriangleMesh out;
    out.name = g.name.empty() ? cat("mesh ", i) : g.name;
    bool normals = true;
    std::vector<Vec3f> all_normals;
    std::vector<uint32_t> face_materials;
    for (size_t k = 0; k < g.primitives.size(); ++k) {
      const tinygltf::Primitive& p = g.primitives[k];
      const std::string pp = cat("$.meshes[", i, "].primitives[", k, "]");
      if (p.mode < 0 || p.mode > 6) fail(pp + ".mode", cat(p.mode, " is no primitive mode (0..6)"));
      if (p.mode < 4) {
        static constexpr const char* kNames[] = {"points", "lines", "a line loop", "a line strip"};
        warning(pp + ".mode", cat(p.mode, " (", kNames[p.mode], ") is not a triangle mode; the primitive is skipped"));
        continue;
      }
      const auto position = p.attributes.find("POSITION");
      if (position == p.attributes.end()) {
        warning(pp + ".attributes", "no POSITION; the primitive is skipped");
        continue;
      }
      if (p.extensions.count("KHR_draco_mesh_compression")) {
        const int a = position->second;
        if (a < 0 || size_t(a) >= m_.accessors.size() || m_.accessors[size_t(a)].bufferView < 0)
          fail(pp + ".extensions.KHR_draco_mesh_compression", "Draco-compressed primitives are not supported");
        warning(pp + ".extensions.KHR_draco_mesh_compression", "not supported; the uncompressed accessors are read");
      }
      const std::string ap = pp + ".attributes.POSITION";
      const std::vector<Vec3f> positions = vectors(view(position->second, ap, TINYGLTF_TYPE_VEC3, {TINYGLTF_COMPONENT_TYPE_FLOAT}));
      for (size_t v = 0; v < positions.size(); ++v)
        if (!in_coordinate_range(positions[v]))
          fail(ap, cat("vertex ", v, " (", positions[v].x, ", ", positions[v].y, ", ", positions[v].z,
                       ") is outside the supported coordinate range |x| <= 1073741824 (2^30)"));
      std::vector<uint32_t> corners;
      if (p.indices >= 0) {
        const std::string ip = pp + ".indices";
        corners = indices(view(p.indices, ip, TINYGLTF_TYPE_SCALAR,
                               {TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
                                TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT}));
        for (size_t c = 0; c < corners.size(); ++c)
          if (corners[c] >= positions.size())
            fail(ip, cat("index ", corners[c], " (element ", c, ") is out of range (", positions.size(), " vertices)"));
      } else {
        corners.resize(positions.size());
        for (size_t c = 0; c < corners.size(); ++c) corners[c] = uint32_t(c);
      }
      const std::vector<uint32_t> triangles = triangulate(corners, p.mode);
      if (triangles.empty()) {
        warning(pp, "no triangle; the primitive is skipped");
        continue;
      }
      const auto normal = p.attributes.find("NORMAL");
      if (normal == p.attributes.end()) {
        normals = false;
      } else if (normals) {
        const std::string np = pp + ".attributes.NORMAL";
        std::vector<Vec3f> n = vectors(view(normal->second, np, TINYGLTF_TYPE_VEC3, {TINYGLTF_COMPONENT_TYPE_FLOAT}));
        if (n.size() != positions.size()) fail(np, cat(n.size(), " normals for ", positions.size(), " positions"));
        for (Vec3f& x : n)
          if (!is_finite(x)) x = Vec3f{};  // a zero normal: the geometric one is used there
        all_normals.insert(all_normals.end(), n.begin(), n.end());
      }
      const uint64_t base = out.positions.size();
      if (base + positions.size() >= kInvalidId) fail(pp, "the mesh has more than 2^32 vertices");
      const uint32_t mat = material(p.material, pp + ".material");
      for (uint32_t c : triangles) out.indices.push_back(uint32_t(base) + c);
      face_materials.insert(face_materials.end(), triangles.size() / 3, mat);
      out.positions.insert(out.positions.end(), positions.begin(), positions.end());
    }
    if (normals) {
      out.normals = std::move(all_normals);
    } else if (!all_normals.empty()) {
      warning(cat("$.meshes[", i, "]"), "some primitives have no NORMAL; the mesh's normals are not used");
    }
    if (!face_materials.empty() && std::all_of(face_materials.begin(), face_materials.end(),
                                               [&](uint32_t m) { return m == face_materials[0]; })) {
      out.material = face_materials[0];
    } else {
      out.face_materials = std::move(face_materials);
    }
    return out;
  }

  /// The corners of a primitive of `mode` (4 triangles, 5 strip, 6 fan) as triangles.
  static std::vector<uint32_t> triangulate(const std::vector<uint32_t>& c, int mode) {
    std::vector<uint32_t> t;
    if (mode == TINYGLTF_MODE_TRIANGLES) {
      t.assign(c.begin(), c.begin() + ptrdiff_t(c.size() / 3 * 3));
    } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
      for (size_t i = 0; i + 2 < c.size(); ++i)  // every other triangle turned to keep the winding
        t.insert(t.end(), i % 2 ? std::initializer_list<uint32_t>{c[i + 1], c[i], c[i + 2]}
                                : std::initializer_list<uint32_t>{c[i], c[i + 1], c[i + 2]});
    } else {
      for (size_t i = 1; i + 1 < c.size(); ++i) t.insert(t.end(), {c[0], c[i], c[i + 1]});
    }
    return t;
  }

  /// glTF mesh i where `use` places it: baked into world coordinates by one node, stored once
  /// and instanced by several.
  void place_mesh(int i, const MeshUse& use) {
    TriangleMesh mesh = convert(i);
    if (mesh.indices.empty()) return;
    const std::string mp = cat("$.meshes[", i, "]");
    std::vector<std::pair<Matrix, int>> placements;
    for (const auto& [to_world, node] : use.placements) {
      if (!inverse(to_world)) {
        warning(cat("$.nodes[", node, "]"), "its transform is singular (a zero scale); its mesh is not placed");
        continue;
      }
      placements.emplace_back(to_world, node);
    }
    if (placements.empty()) return;
    if (placements.size() == 1) {
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
      try {
        scene_.add_instance(id, Affine3f(to_world));
      } catch (const Error& e) {
        fail(cat("$.nodes[", node, "]"), e.what());
      }
    }
  }

  const std::string& file_;
  const tinygltf::Model& m_;
  Scene& scene_;
  std::vector<uint32_t> materials_;  ///< glTF material -> scene material (kInvalidId: not added yet)
  std::vector<Placed> placed_;
  bool camera_set_ = false;
};

}  // namespace

void load_gltf(const std::string& path, Scene& scene) {
  const MappedFile file(path);
  if (file.size() > kMaxGltfBytes)
    throw Error(cat(path, ": ", file.size(), " bytes, more than the ", kMaxGltfBytes, " a glTF file may have"));
  const std::string_view bytes(file.data(), file.size());
  const bool binary = bytes.size() >= 4 && bytes.substr(0, 4) == "glTF";
  const std::string_view json = binary ? glb_json(path, bytes) : bytes;
  check_json_depth(path, json);  // tinygltf's parser recurses

  const size_t slash = path.find_last_of('/');
  FileAccess access{slash == std::string::npos ? std::string() : path.substr(0, slash + 1), {}, {}};
  tinygltf::TinyGLTF loader;
  loader.SetFsCallbacks({&file_exists, &expand_path, &read_whole_file, &write_whole_file, &access});
  loader.SetImageLoader(&skip_image, nullptr);
  tinygltf::Model model;
  std::string err, warnings;
  // tinygltf joins a URI to the base folder with a '/', so "" would read "/x.bin": use ".".
  const std::string base = access.base_dir.empty() ? std::string(".") : slash == 0 ? std::string("/")
                                                                                      : access.base_dir.substr(0, slash);
  const bool ok = binary ? loader.LoadBinaryFromMemory(&model, &err, &warnings,
                                                       reinterpret_cast<const unsigned char*>(bytes.data()),
                                                       unsigned(bytes.size()), base)
                         : loader.LoadASCIIFromString(&model, &err, &warnings, bytes.data(), unsigned(bytes.size()), base);
  if (!ok) {
    if (!access.failure.empty())
      throw Error(cat(path, ": ", buffer_path(json, access.base_dir.empty() ? "./" : access.base_dir, access.failed_path),
                      ": ", access.failure));
    throw Error(cat(path, ": ", first_line(err)));
  }
  GltfReader(path, model, scene).read();
}

}  // namespace rp
