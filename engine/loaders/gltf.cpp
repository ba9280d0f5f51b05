/// glTF 2.0 scenes (.gltf with external or data-URI buffers, .glb) through tinygltf 2.7
/// (engine/loaders/tinygltf_impl.cpp), mapped onto the Scene:
///
/// - the default scene (`scene`), or the first when there is none; its node hierarchy walked
///   from its roots, each node's transform its `matrix` (column-major, which must be affine)
///   or T * R * S from `translation`, `rotation` (a unit quaternion x, y, z, w: its length
///   within 0.00769 of 1, glTF-Validator's tolerance, and normalised on reading) and `scale`,
///   composed parent * child in double;
/// - meshes: every triangle primitive (mode 4, and strips 5 and fans 6 turned into triangles;
///   indexed or not, indices of an unsigned integer type: componentType 5121, 5123 or 5125) of
///   a glTF mesh becomes part of one TriangleMesh, a primitive's material on its triangles;
///   NORMAL kept when every primitive of the mesh has it. A mesh one node places is baked into
///   world coordinates; a mesh several nodes place is stored once in its own coordinates and
///   each node is an instance (Scene::add_instance);
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
///   every other material extension; images are neither decoded nor opened;
/// - external buffers only from the glTF's folder and below: a buffer's URI, %-decoded as
///   tinygltf decodes it, is a relative path that must stay inside that folder both as written
///   ("../x.bin", "..%2Fx.bin" and "/etc/x" are refused, "sub/../x.bin" is read) and with every
///   symbolic link followed (realpath(3) against the folder's canonical path: a link inside the
///   folder to a file outside it is refused, one to a file inside it is read).
///
/// Refused with one line naming the file and the JSON path, first by the JSON check before
/// tinygltf reads the JSON (check_gltf_json, engine/loaders/gltf_check.h, lists each): values
/// of the sections raypack uses that have the wrong type or lie outside glTF's range (indices
/// naming nothing, negative offsets, counts or lengths of 0, non-numbers in a transform,
/// factors outside [0, 1], a rotation that is not a unit quaternion, an unknown componentType,
/// accessor, camera or light type, a required property missing), since
/// tinygltf turns most of them into defaults without a word; buffer URIs leading out of the
/// glTF's folder; and objects that would take tinygltf far more memory than the file (below).
/// Then: Draco-compressed primitives without an uncompressed fallback, sparse accessors that
/// a primitive reads (sparse ones it does not read, a morph target's, are left alone), accessors whose
/// elements do not fit their bufferView and buffer (bad offsets, strides, absurd counts:
/// checked before anything is allocated for them), indices that name no vertex or are not of
/// an unsigned integer type, positions that are not 3 floats or lie outside the coordinate
/// range, node cycles and nodes with two parents, non-affine matrices, buffers missing or
/// unreadable (a device, a directory: engine/input_file.h's rule) or of another size than
/// their byteLength, required extensions that change geometry (Draco, meshopt, mesh
/// quantization, GPU instancing), an empty file or a truncated GLB, and whatever tinygltf
/// still refuses (its first line). Warned about and skipped: points and lines, primitives
/// without positions, nodes whose transform is singular, a camera or light that cannot be
/// used; the warnings of one kind are one line, with how many more there were. Size limits:
/// the file itself and each external buffer at most kMaxGltfBytes (a .glb below 4 GiB,
/// tinygltf's own limit), JSON nested at most 64 levels (checked before parsing, as every JSON
/// reader of raypack).
///
/// Memory: tinygltf builds every object the JSON lists, each far larger than its text (a
/// tinygltf::Node is 456 bytes, a Material 2,144, where "{}," is 3 bytes of JSON), after its
/// own JSON DOM. So before tinygltf parses, what it would take is estimated: 12 bytes per byte
/// of JSON for the DOM (nlohmann-json's: 7 to 13 on glTF files, up to 28 on empty objects)
/// plus, for each kind of object, its count times the size of its tinygltf type (every JSON
/// value under "extras" or "extensions" a tinygltf::Value). A file is refused when that
/// exceeds both 256 MiB and 32 bytes per byte of input (the file and each external buffer's
/// byteLength, so that a GLB's BIN chunk or a large .bin gives its objects room): 32 is the
/// DOM's 12 plus room for objects of any ordinary size (a named node with a transform
/// takes about 4 bytes per byte of its JSON, a named material about 18), which a file of bare
/// "{}" objects or a few bytes each exceeds many times. Not counted: raypack's own DOM of the
/// JSON, the buffers' bytes, and what the Scene takes.
///
/// Over 600 lines: the tinygltf glue (file callbacks, GLB chunks, tinygltf's messages) and the
/// mapping onto the Scene are one load's steps sharing its messages; the JSON check before them
/// is engine/loaders/gltf_check.cpp.

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <unistd.h>

#include "engine/error.h"
#include "engine/input_file.h"
#include "engine/json_text.h"
#include "engine/loaders/gltf_check.h"
#include "engine/memory_reserve.h"
#include "engine/loaders/load.h"
#include "engine/loaders/tinygltf_config.h"
#include "engine/text.h"

namespace rp {
namespace {

/// What the file-system callbacks give tinygltf: the external buffers the JSON check found
/// inside the glTF's folder, and the first failure, reported with its buffer's JSON path.
struct FileAccess {
  std::vector<GltfBufferFile> buffers;
  size_t next = 0;  ///< the first not yet read: tinygltf reads the buffers in order
  std::optional<size_t> failed;
  std::string failure;
};

/// tinygltf asks whether a candidate path exists before reading it (its base folder joined
/// with the URI, then "./" joined with it): only a path the JSON check resolved is raypack's
/// answer, so no other file is ever looked for or opened.
bool file_exists(const std::string& path, void* user) {
  const FileAccess& a = *static_cast<const FileAccess*>(user);
  return std::any_of(a.buffers.begin() + ptrdiff_t(a.next), a.buffers.end(),
                     [&](const GltfBufferFile& b) { return b.path == path; });
}

/// No expansion (tinygltf's own runs wordexp on the path).
std::string expand_path(const std::string& path, void*) { return path; }

/// Reads an external buffer by raypack's input rule: a regular file (not a device, FIFO or
/// directory) of at most kMaxGltfBytes, exactly its byteLength, its size known before anything
/// is allocated.
bool read_whole_file(std::vector<unsigned char>* out, std::string* err, const std::string& path, void* user) {
  FileAccess& a = *static_cast<FileAccess*>(user);
  const auto it = std::find_if(a.buffers.begin() + ptrdiff_t(a.next), a.buffers.end(),
                               [&](const GltfBufferFile& b) { return b.path == path; });
  if (it == a.buffers.end()) {
    if (err) *err += cat(path, ": not a buffer the glTF names");
    return false;
  }
  a.next = size_t(it - a.buffers.begin()) + 1;
  try {
    uint64_t size = 0;
    const std::string& file = it->file;
    const int fd = open_regular_file(file, size);
    ::close(fd);
    if (size > kMaxGltfBytes)
      throw Error(cat(file, ": ", size, " bytes, more than the ", kMaxGltfBytes, " a buffer may have"));
    if (size != it->byte_length)
      throw Error(cat(file, ": ", size, " bytes, not the ", it->byte_length, " its byteLength says"));
    const std::string bytes = read_file(file);
    out->assign(bytes.begin(), bytes.end());
    return true;
  } catch (const Error& e) {
    if (!a.failed) {
      a.failed = size_t(it - a.buffers.begin());
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

/// A GLB's JSON text (its first chunk) and the bytes of its BIN chunk (the second, when
/// there is one).
struct GlbChunks {
  std::string_view json;
  std::optional<uint64_t> bin_bytes;
};

/// The chunks of a GLB, after checking the 12-byte header and every chunk against the file's
/// size: each chunk's 8-byte header and the length it claims inside the file, the second chunk
/// (when there is one) BIN, the last ending where the file does. tinygltf 2.7 checks the BIN
/// chunk's length without its header and would copy up to 8 bytes past the file. Throws one
/// line naming the file for a truncated or malformed one.
GlbChunks glb_chunks(const std::string& path, std::string_view bytes) {
  const auto u32 = [&](size_t at) {
    uint32_t v;
    std::memcpy(&v, bytes.data() + at, 4);
    return v;
  };
  if (bytes.size() < 20)
    throw Error(cat(path, ": truncated GLB: ", bytes.size(), " bytes, its headers need 20"));
  if (bytes.substr(0, 4) != "glTF") throw Error(cat(path, ": not a GLB: its first 4 bytes are not \"glTF\""));
  if (u32(4) != 2) throw Error(cat(path, ": GLB version ", u32(4), " (2 is read)"));
  if (u32(8) != bytes.size())
    throw Error(cat(path, ": ", u32(8) < bytes.size() ? "GLB with trailing bytes" : "truncated GLB", ": the header says ",
                    u32(8), " bytes, the file has ", bytes.size()));
  const uint64_t json_bytes = u32(12);
  if (u32(16) != 0x4E4F534Au) throw Error(cat(path, ": GLB whose first chunk is not JSON"));
  if (20 + json_bytes > bytes.size())
    throw Error(cat(path, ": truncated GLB: its JSON chunk says ", json_bytes, " bytes, ", bytes.size() - 20, " follow"));
  GlbChunks out{bytes.substr(20, size_t(json_bytes)), std::nullopt};
  for (uint64_t at = 20 + json_bytes; at < bytes.size();) {
    const uint64_t left = bytes.size() - at;
    if (left < 8)
      throw Error(cat(path, ": truncated GLB: the chunk at byte ", at, " has ", left, " of its 8 header bytes"));
    const bool second = at == 20 + json_bytes;
    if (second && u32(at + 4) != 0x004E4942u)
      throw Error(cat(path, ": GLB whose second chunk is of type ", gltf_quoted(bytes.substr(at + 4, 4)), ", not BIN"));
    const uint64_t length = u32(at);
    if (length > left - 8)
      throw Error(cat(path, ": truncated GLB: its ", second ? std::string("BIN chunk") : cat("chunk at byte ", at),
                      " says ", length, " bytes, ", left - 8, " follow"));
    if (second) out.bin_bytes = length;
    at += 8 + length;
  }
  return out;
}

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
    try {
      read_scene();
    } catch (...) {
      print_warnings();
      throw;
    }
    print_warnings();
  }

 private:
  void read_scene() {
    check_required_extensions();
    if (m_.scenes.empty()) fail("$.scenes", "the file has no scene");
    walk(m_.defaultScene >= 0 ? m_.defaultScene : 0);
    std::vector<MeshUse> uses(m_.meshes.size());
    for (const Placed& p : placed_) uses[size_t(p.mesh)].placements.emplace_back(p.to_world, p.node);
    for (size_t i = 0; i < uses.size(); ++i)
      if (!uses[i].placements.empty()) place_mesh(int(i), uses[i]);
  }

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
  void warning(const std::string& path, const std::string& what) {
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
  /// Prints the warnings kept, each once: "(and 1,599 more nodes like it)" after the first of a
  /// kind, the elements named as the last array of its path.
  void print_warnings() {
    for (const Warning& w : warnings_) {
      std::string more;
      if (w.more > 0) {
        // The elements are named by the path's last array: "$.nodes[7]" -> "nodes".
        const size_t open = w.path.rfind('[');
        size_t start = open == std::string::npos ? 0 : open;
        while (start > 0 && w.path[start - 1] != '.') --start;
        const std::string noun =
            open == std::string::npos ? std::string("elements") : w.path.substr(start, open - start);
        more = cat(" (and ", grouped(w.more), " more ", noun, " like it)");
      }
      warn(cat(file_, ": ", w.path, ": ", w.what, more));
    }
    warnings_.clear();
  }

  /// Extensions the file requires that change what its geometry is: refused, as the geometry
  /// would be wrong without them. Other required extensions (textures, materials) are warned
  /// about: raypack does not use what they change.
  void check_required_extensions() {
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

  // ---- the node hierarchy ----

  struct Placed {
    int mesh, node;
    Matrix to_world;
  };

  /// The local transform of node n (its numbers checked by check_gltf_json: as many as glTF
  /// says, finite, the rotation a unit quaternion within its tolerance, made exactly one
  /// here).
  Matrix local(int n) const {
    const tinygltf::Node& node = m_.nodes[size_t(n)];
    if (!node.matrix.empty()) {
      const std::optional<Matrix> a = affine_of(node.matrix);
      if (!a) fail(cat("$.nodes[", n, "].matrix"), "not an affine transform (its last row is not 0 0 0 1)");
      return *a;
    }
    std::array<double, 3> t{0, 0, 0}, s{1, 1, 1};
    std::array<double, 4> q{0, 0, 0, 1};
    const auto take = [](const std::vector<double>& v, auto& out) {
      if (v.size() == out.size()) std::copy(v.begin(), v.end(), out.begin());
    };
    take(node.translation, t);
    take(node.rotation, q);
    take(node.scale, s);
    const double len = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    for (double& c : q) c /= len;
    return trs(t, q, s);
  }

  /// Walks scene s from its roots: every node once (a node met again is in a cycle or has two
  /// parents, which glTF forbids), depth-first without recursion.
  void walk(int s) {
    const tinygltf::Scene& scene = at(m_.scenes, s, "$.scene");
    std::vector<uint8_t> state(m_.nodes.size(), 0);  // 0 unseen, 1 on the current path, 2 done
    struct Frame {
      int node;
      Matrix to_world;
      size_t next_child;
    };
    std::vector<Frame> stack;
    const auto enter = [&](int n, const Matrix& parent, const std::string& path) {
      at(m_.nodes, n, path);
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
      at(m_.meshes, node.mesh, path + ".mesh");
      placed_.push_back({node.mesh, n, to_world});
    }
    if (node.camera >= 0) camera(n, to_world);
    if (const auto it = node.extensions.find("KHR_lights_punctual"); it != node.extensions.end()) light(n, it->second, to_world);
  }

  // ---- cameras and lights ----

  void camera(int n, const Matrix& to_world) {
    if (camera_set_) return;  // the first one met
    const tinygltf::Node& node = m_.nodes[size_t(n)];
    const tinygltf::Camera& c = at(m_.cameras, node.camera, cat("$.nodes[", n, "].camera"));
    const std::string cp = cat("$.cameras[", node.camera, "]");
    if (c.type != "perspective") {
      warning(cp, cat("a ", gltf_quoted(c.type), " camera is not supported; it is not used"));
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

  /// The light `ext` (a node's KHR_lights_punctual object, its integer "light" and the light's
  /// type and color checked by check_gltf_json) names.
  void light(int n, const tinygltf::Value& ext, const Matrix& to_world) {
    const int l = ext.Get("light").GetNumberAsInt();
    const tinygltf::Light& light = at(m_.lights, l, cat("$.nodes[", n, "].extensions.KHR_lights_punctual.light"));
    const std::string lp = cat("$.extensions.KHR_lights_punctual.lights[", l, "]");
    Vec3d colour(1.0);
    if (light.color.size() == 3) colour = {light.color[0], light.color[1], light.color[2]};
    const Vec3f power = Vec3f(colour * light.intensity);
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
    const tinygltf::Accessor& acc = at(m_.accessors, a, use);
    const std::string ap = cat("$.accessors[", a, "]");
    // Refused where the reader reads one only: a model may have sparse accessors elsewhere
    // (morph targets, animation), which it does not read.
    if (acc.sparse.isSparse) fail(ap + ".sparse", "sparse accessors are not supported");
    if (acc.type != type)
      fail(ap + ".type", cat(use, " needs ", type == TINYGLTF_TYPE_SCALAR ? "SCALAR" : "VEC3", " elements"));
    if (std::find(component_types.begin(), component_types.end(), acc.componentType) == component_types.end()) {
      std::string list;
      for (int t : component_types) list += cat(list.empty() ? "" : ", ", t);
      fail(ap + ".componentType", cat(acc.componentType, " is not a component type ", use, " can have (", list, ")"));
    }
    if (acc.bufferView < 0) fail(ap, "has no bufferView (all zeros, or data in an extension): not supported");
    const tinygltf::BufferView& bv = at(m_.bufferViews, acc.bufferView, ap + ".bufferView");
    const std::string vp = cat("$.bufferViews[", acc.bufferView, "]");
    const tinygltf::Buffer& buffer = at(m_.buffers, bv.buffer, vp + ".buffer");
    const uint64_t buffer_bytes = buffer.data.size();
    if (uint64_t(bv.byteOffset) > buffer_bytes || uint64_t(bv.byteLength) > buffer_bytes - bv.byteOffset)
      fail(vp, cat(bv.byteLength, " bytes from byte ", bv.byteOffset, " do not fit in buffer ", bv.buffer, "'s ",
                   buffer_bytes, " bytes"));
    const uint64_t components = type == TINYGLTF_TYPE_SCALAR ? 1 : 3;
    const uint64_t element = components * uint64_t(tinygltf::GetComponentSizeInBytes(uint32_t(acc.componentType)));
    const uint64_t stride = bv.byteStride == 0 ? element : bv.byteStride;
    if (stride < element || stride > 252)
      fail(vp + ".byteStride", cat(bv.byteStride, " is outside [", element, ", 252] for ", element, "-byte elements"));
    const uint64_t count = acc.count, offset = acc.byteOffset;
    // The last element ends at offset + (count - 1) * stride + element: no product overflows,
    // count being checked against the bytes first.
    if (offset > bv.byteLength || count - 1 > (bv.byteLength - offset) / stride ||
        offset + (count - 1) * stride + element > bv.byteLength)
      fail(ap, cat(count, " elements of ", element, " bytes, ", stride, " apart from byte ", offset, ", do not fit in ",
                   vp.substr(2), "'s ", bv.byteLength, " bytes"));
    return {buffer.data.data() + bv.byteOffset + offset, size_t(count), size_t(stride), acc.componentType};
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
      guaranteed(p.mode >= 0 && p.mode <= 6, pp + ".mode");
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
      const std::string ap = pp + ".attributes.POSITION";
      if (p.extensions.count("KHR_draco_mesh_compression")) {
        if (at(m_.accessors, position->second, ap).bufferView < 0)
          fail(pp + ".extensions.KHR_draco_mesh_compression", "Draco-compressed primitives are not supported");
        warning(pp + ".extensions.KHR_draco_mesh_compression", "not supported; the uncompressed accessors are read");
      }
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
            fail(ip, cat("element ", c, ": ", corners[c], " is not a vertex index (the primitive has ",
                         positions.size(), " vertices)"));
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
        warning(cat("$.nodes[", node, "]"),
                "its transform is singular (a zero scale) or too large to invert; its mesh is not placed");
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
  std::vector<Warning> warnings_;
};

}  // namespace

void load_gltf(const std::string& path, Scene& scene) {
  const MappedFile file(path);
  if (file.size() > kMaxGltfBytes)
    throw Error(cat(path, ": ", file.size(), " bytes, more than the ", kMaxGltfBytes, " a glTF file may have"));
  if (file.size() == 0) throw Error(cat(path, ": empty file"));
  const std::string_view bytes(file.data(), file.size());
  const bool binary = bytes.substr(0, 4) == "glTF" || lower_extension(path) == ".glb";
  const GlbChunks glb = binary ? glb_chunks(path, bytes) : GlbChunks{bytes, std::nullopt};
  check_json_depth(path, glb.json);  // nlohmann's parser and tinygltf's recurse
  // Outlives both JSON documents (this one and tinygltf's): see engine/memory_reserve.h.
  const MemoryReserve reserve(json_unwind_reserve(glb.json.size()));

  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(glb.json.begin(), glb.json.end());
  } catch (const nlohmann::json::parse_error& e) {
    const TextPosition at = position_of(glb.json, e.byte);
    throw Error(cat(path, ": line ", at.line, ", column ", at.column, ": ", json_reason(e.what())));
  } catch (const nlohmann::json::exception& e) {
    throw Error(cat(path, ": ", json_reason(e.what())));  // a number too large for a double
  }
  // tinygltf joins a URI to the base folder with a '/', so "" would read "/x.bin": use ".".
  const std::string parent = std::filesystem::path(path).parent_path().string();
  const std::string base = parent.empty() ? std::string(".") : parent;
  FileAccess access;
  access.buffers = check_gltf_json({path, base, binary, glb.bin_bytes, bytes.size(), glb.json.size()}, doc);

  tinygltf::TinyGLTF loader;
  loader.SetFsCallbacks({&file_exists, &expand_path, &read_whole_file, &write_whole_file, &access});
  loader.SetImageLoader(&skip_image, nullptr);
  tinygltf::Model model;
  std::string err, warnings;
  bool ok = false;
  try {
    ok = binary ? loader.LoadBinaryFromMemory(&model, &err, &warnings,
                                              reinterpret_cast<const unsigned char*>(bytes.data()),
                                              unsigned(bytes.size()), base)
                : loader.LoadASCIIFromString(&model, &err, &warnings, bytes.data(), unsigned(bytes.size()), base);
  } catch (const std::bad_alloc&) {
    throw;  // out of memory: reported as such by the caller
  } catch (const std::exception& e) {
    // What the JSON check lets through should never make tinygltf throw; if it does, the
    // message still names the file.
    throw Error(cat(path, ": tinygltf failed: ", one_line(e.what())));
  }
  if (!ok) {
    if (access.failed) {
      const GltfBufferFile& b = access.buffers[*access.failed];
      throw Error(cat(path, ": $.buffers[", b.index, "].uri: ", gltf_quoted(b.uri), ": ", access.failure));
    }
    if (err.find("Failed to decode 'uri'") != std::string::npos) {
      // A data URI whose bytes are not its buffer's byteLength: tinygltf quotes the whole URI.
      const auto buffers = doc.find("buffers");
      for (size_t i = 0; buffers != doc.end() && i < buffers->size(); ++i) {
        const nlohmann::json& b = (*buffers)[i];
        const auto uri = b.find("uri");
        if (uri == b.end() || !tinygltf::IsDataURI(uri->get<std::string>())) continue;
        std::vector<unsigned char> data;
        std::string mime;
        tinygltf::DecodeDataURI(&data, mime, uri->get<std::string>(), 0, false);
        const uint64_t length = b.at("byteLength").get<uint64_t>();
        if (data.size() != length)
          throw Error(cat(path, ": $.buffers[", i, "].uri: its data holds ", data.size(), " bytes, not the ", length,
                          " of its byteLength"));
      }
    }
    throw Error(cat(path, ": ", first_line(err)));
  }
  GltfReader(path, model, scene).read();
}

}  // namespace rp
