#pragma once
// glTF files the tests (and the fuzz corpus) build from code, through tinygltf's own model and
// writer: no glTF JSON or base64 written by hand. GltfBuilder appends meshes, nodes and the
// bytes of their accessors to one buffer; write_gltf writes the model as .gltf (buffers as
// data URIs or an external .bin) or .glb, optionally editing the JSON document first with
// nlohmann-json (for what tinygltf's writer cannot express: a sparse accessor, a buffer URI
// naming a device).

#include <cmath>
#include <array>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <iterator>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "base/math.h"
#include "core/affine.h"
#include "io/loaders/tinygltf_config.h"

namespace rp::test {

/// How write_gltf stores the buffers.
enum class GltfForm {
  embedded,  ///< .gltf, every buffer a data URI
  external,  ///< .gltf and the first buffer as <name>.bin beside it
  binary,    ///< .glb, the first buffer its BIN chunk
};

class GltfBuilder {
 public:
  GltfBuilder() {
    model.asset.version = "2.0";
    model.asset.generator = "raypack tests";
    model.buffers.resize(1);
  }

  /// A bufferView over `bytes` appended to buffer 0 (4-byte aligned), with `stride` (0: none).
  int view(const void* bytes, size_t size, size_t stride = 0) {
    std::vector<unsigned char>& data = model.buffers[0].data;
    while (data.size() % 4) data.push_back(0);
    tinygltf::BufferView v;
    v.buffer = 0;
    v.byteOffset = data.size();
    v.byteLength = size;
    v.byteStride = stride;
    data.insert(data.end(), static_cast<const unsigned char*>(bytes), static_cast<const unsigned char*>(bytes) + size);
    model.bufferViews.push_back(v);
    return int(model.bufferViews.size() - 1);
  }

  int accessor(int view, int component_type, int type, size_t count, size_t offset = 0) {
    tinygltf::Accessor a;
    a.bufferView = view;
    a.componentType = component_type;
    a.type = type;
    a.count = count;
    a.byteOffset = offset;
    model.accessors.push_back(a);
    return int(model.accessors.size() - 1);
  }

  /// An accessor of 3-float vectors (positions or normals); `stride` > 12 interleaves padding.
  int vectors(const std::vector<Vec3f>& v, size_t stride = 0) {
    std::vector<float> words;
    const size_t step = stride ? stride / 4 : 3;
    for (const Vec3f& p : v) {
      words.insert(words.end(), {p.x, p.y, p.z});
      words.resize(words.size() + step - 3, -7.0f);
    }
    const int bv = view(words.data(), words.size() * 4, stride);
    return accessor(bv, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, v.size());
  }

  /// An accessor of floats of `type` (SCALAR, VEC3 or VEC4: 1, 3 or 4 floats an element).
  int floats(const std::vector<float>& v, int type) {
    const size_t n = type == TINYGLTF_TYPE_SCALAR ? 1 : type == TINYGLTF_TYPE_VEC3 ? 3 : 4;
    return accessor(view(v.data(), v.size() * 4), TINYGLTF_COMPONENT_TYPE_FLOAT, type, v.size() / n);
  }

  /// A channel of animation `animation` (made when it is the next) moving the `path`
  /// ("translation", "rotation" or "scale") of `node`, by a sampler of its own: keyframe
  /// `times` and their `values` (3 or 4 floats an element; 3 elements a keyframe, in-tangent,
  /// value, out-tangent, for "CUBICSPLINE"). Returns the sampler's index in the animation.
  int animate(int node, const std::string& path, const std::vector<float>& times, const std::vector<float>& values,
              const std::string& interpolation = "LINEAR", size_t animation = 0) {
    const int input = floats(times, TINYGLTF_TYPE_SCALAR);
    const int output = floats(values, path == "rotation" ? TINYGLTF_TYPE_VEC4 : TINYGLTF_TYPE_VEC3);
    return animate(node, path, input, output, interpolation, animation);
  }

  /// The same with a sampler of accessors `input` (times) and `output` (values) made already.
  int animate(int node, const std::string& path, int input, int output, const std::string& interpolation,
              size_t animation = 0) {
    if (model.animations.size() <= animation) model.animations.resize(animation + 1);
    tinygltf::AnimationSampler s;
    s.input = input;
    s.output = output;
    s.interpolation = interpolation;
    tinygltf::Animation& a = model.animations[animation];
    a.samplers.push_back(s);
    tinygltf::AnimationChannel c;
    c.sampler = int(a.samplers.size() - 1);
    c.target_node = node;
    c.target_path = path;
    a.channels.push_back(c);
    return c.sampler;
  }

  /// An accessor of indices stored as `component_type` (unsigned byte, short or int).
  int indices(const std::vector<uint32_t>& idx, int component_type) {
    std::vector<unsigned char> bytes;
    for (uint32_t i : idx) {
      const size_t n = component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE    ? 1
                       : component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ? 2
                                                                                  : 4;
      for (size_t k = 0; k < n; ++k) bytes.push_back(static_cast<unsigned char>(i >> (8 * k)));  // little-endian
    }
    const int bv = view(bytes.data(), bytes.size());
    return accessor(bv, component_type, TINYGLTF_TYPE_SCALAR, idx.size());
  }

  /// A primitive of accessors (normals -1: none; indices -1: none) in `mode`.
  static tinygltf::Primitive primitive(int positions, int indices = -1, int normals = -1, int material = -1,
                                       int mode = TINYGLTF_MODE_TRIANGLES) {
    tinygltf::Primitive p;
    p.attributes["POSITION"] = positions;
    if (normals >= 0) p.attributes["NORMAL"] = normals;
    p.indices = indices;
    p.material = material;
    p.mode = mode;
    return p;
  }

  int mesh(std::vector<tinygltf::Primitive> primitives, const std::string& name = "") {
    tinygltf::Mesh m;
    m.name = name;
    m.primitives = std::move(primitives);
    model.meshes.push_back(std::move(m));
    return int(model.meshes.size() - 1);
  }

  int material(const Vec3f& base_colour, const Vec3f& emissive = {}, const std::string& name = "") {
    tinygltf::Material m;
    m.name = name;
    m.pbrMetallicRoughness.baseColorFactor = {base_colour.x, base_colour.y, base_colour.z, 1.0};
    m.emissiveFactor = {emissive.x, emissive.y, emissive.z};
    model.materials.push_back(m);
    return int(model.materials.size() - 1);
  }

  /// A node placing `mesh` (-1: none) with children, by translation, rotation (a quaternion
  /// x, y, z, w) and scale (empty: not written).
  int node(int mesh, std::vector<double> translation = {}, std::vector<double> rotation = {},
           std::vector<double> scale = {}, std::vector<int> children = {}) {
    tinygltf::Node n;
    n.mesh = mesh;
    n.translation = std::move(translation);
    n.rotation = std::move(rotation);
    n.scale = std::move(scale);
    n.children = std::move(children);
    model.nodes.push_back(n);
    return int(model.nodes.size() - 1);
  }

  /// A node placing `mesh` by a column-major 4x4 `matrix`.
  int matrix_node(int mesh, std::vector<double> matrix, std::vector<int> children = {}) {
    tinygltf::Node n;
    n.mesh = mesh;
    n.matrix = std::move(matrix);
    n.children = std::move(children);
    model.nodes.push_back(n);
    return int(model.nodes.size() - 1);
  }

  /// The default scene, of `roots`.
  void scene(std::vector<int> roots) {
    tinygltf::Scene s;
    s.nodes = std::move(roots);
    model.scenes.push_back(s);
    model.defaultScene = int(model.scenes.size() - 1);
  }

  tinygltf::Model model;
};

/// Writes `model` to `path` in `form`; `patch`, when given, edits the JSON document before it is
/// written (not for GltfForm::binary). Throws std::runtime_error when tinygltf cannot write.
inline void write_gltf(const tinygltf::Model& model, const std::string& path, GltfForm form,
                       const std::function<void(nlohmann::json&)>& patch = {}) {
  tinygltf::TinyGLTF writer;
  bool ok = false;
  if (form == GltfForm::external) {
    ok = writer.WriteGltfSceneToFile(&model, path, false, false, true, false);
  } else {
    std::ofstream out(path, std::ios::binary);
    ok = writer.WriteGltfSceneToStream(&model, out, true, form == GltfForm::binary) && out.good();
  }
  if (!ok) throw std::runtime_error("tinygltf could not write " + path);
  if (!patch) return;
  if (form == GltfForm::binary) throw std::runtime_error("write_gltf: a .glb cannot be patched");
  std::ifstream in(path);
  nlohmann::json doc = nlohmann::json::parse(std::string(std::istreambuf_iterator<char>(in), {}));
  patch(doc);
  std::ofstream(path, std::ios::binary | std::ios::trunc) << doc.dump(2);
}

/// The bytes of a GLB of JSON document `doc` and, unless empty, a BIN chunk of `bin` (each
/// chunk padded to 4 bytes, JSON with spaces, BIN with zeros): for GLBs whose JSON tinygltf's
/// writer cannot express.
inline std::string glb_bytes(const nlohmann::json& doc, std::string bin) {
  std::string json = doc.dump();
  while (json.size() % 4) json += ' ';
  while (bin.size() % 4) bin += '\0';
  const auto u32 = [](uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); };
  std::string chunks = u32(uint32_t(json.size())) + "JSON" + json;
  if (!bin.empty()) chunks += u32(uint32_t(bin.size())) + std::string("BIN\0", 4) + bin;
  return "glTF" + u32(2) + u32(uint32_t(12 + chunks.size())) + chunks;
}

/// The column-major 4x4 matrix of an affine map (glTF's node "matrix").
inline std::vector<double> column_major(const Affine3d& a) {
  std::vector<double> m(16, 0.0);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) m[size_t(c * 4 + r)] = a.m[r][c];
  m[15] = 1.0;
  return m;
}

/// T * R * S of a glTF node's translation, rotation (x, y, z, w) and scale, in double: the
/// tests' own composition, independent of the loader's matrix formula: each column is a unit
/// axis scaled, then turned by the quaternion (v + 2w (u x v) + 2 u x (u x v), u = (x, y, z)).
inline Affine3d node_transform(const std::vector<double>& t, const std::vector<double>& q, const std::vector<double>& s) {
  Vec3d u(0.0);
  double w = 1.0;
  if (!q.empty()) {
    const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    u = Vec3d(q[0], q[1], q[2]) / n;
    w = q[3] / n;
  }
  Affine3d a;
  for (int j = 0; j < 3; ++j) {
    Vec3d v(0.0);
    v[j] = s.empty() ? 1.0 : s[size_t(j)];
    const Vec3d uv = cross(u, v);
    const Vec3d turned = v + uv * (2.0 * w) + cross(u, uv) * 2.0;
    for (int i = 0; i < 3; ++i) a.m[i][j] = turned[i];
  }
  for (int i = 0; i < 3; ++i) a.m[i][3] = t.empty() ? 0.0 : t[size_t(i)];
  return a;
}

/// A glTF with a node hierarchy (three roots, up to three levels, TRS and matrix nodes, a
/// mirroring scale), one mesh placed by three nodes and others by one, every index type,
/// non-indexed primitives, a triangle strip and fan, two primitives in one mesh, materials;
/// and the same triangles in world coordinates, placed by the tests' own composition
/// (node_transform, compose), for a flattened copy.
struct HierarchyGltf {
  tinygltf::Model model;
  std::vector<std::array<Vec3d, 3>> world_triangles;
  uint32_t pair_mesh_placements = 3;  ///< nodes placing mesh "pair"
};

inline HierarchyGltf hierarchy_gltf() {
  GltfBuilder b;
  const int red = b.material({0.8f, 0.1f, 0.1f}, {}, "red"), green = b.material({0.1f, 0.7f, 0.2f}, {0.1f, 0.2f, 0.3f}, "green");
  // Each mesh's triangles as the tests triangulate them, in its own coordinates.
  std::vector<std::vector<std::array<Vec3d, 3>>> local;
  const auto triangles_of = [](const std::vector<Vec3f>& p, const std::vector<uint32_t>& c, int mode) {
    std::vector<std::array<Vec3d, 3>> t;
    const auto v = [&](uint32_t i) { return Vec3d(p[i]); };
    if (mode == TINYGLTF_MODE_TRIANGLES)
      for (size_t i = 0; i + 2 < c.size(); i += 3) t.push_back({v(c[i]), v(c[i + 1]), v(c[i + 2])});
    if (mode == TINYGLTF_MODE_TRIANGLE_STRIP)
      for (size_t i = 0; i + 2 < c.size(); ++i)
        t.push_back(i % 2 ? std::array<Vec3d, 3>{v(c[i + 1]), v(c[i]), v(c[i + 2])}
                          : std::array<Vec3d, 3>{v(c[i]), v(c[i + 1]), v(c[i + 2])});
    if (mode == TINYGLTF_MODE_TRIANGLE_FAN)
      for (size_t i = 1; i + 1 < c.size(); ++i) t.push_back({v(c[0]), v(c[i]), v(c[i + 1])});
    return t;
  };
  const auto all = [](size_t n) {
    std::vector<uint32_t> c(n);
    for (size_t i = 0; i < n; ++i) c[i] = uint32_t(i);
    return c;
  };
  // "pair": a unit square of two triangles, u16 indices, normals; placed three times.
  const std::vector<Vec3f> square{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  const std::vector<uint32_t> square_idx{0, 1, 2, 0, 2, 3};
  const int pair = b.mesh({GltfBuilder::primitive(b.vectors(square), b.indices(square_idx, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT),
                                                  b.vectors(std::vector<Vec3f>(4, Vec3f(0, 0, 1))), red)},
                          "pair");
  local.push_back(triangles_of(square, square_idx, TINYGLTF_MODE_TRIANGLES));
  // "mixed": a tetrahedron by u8 indices (interleaved positions, 16-byte stride), then two
  // non-indexed triangles.
  const std::vector<Vec3f> tetra{{0, 0, 0}, {0.6f, 0, 0.1f}, {0.2f, 0.5f, 0}, {0.25f, 0.2f, 0.6f}};
  const std::vector<uint32_t> tetra_idx{0, 2, 1, 0, 1, 3, 1, 2, 3, 2, 0, 3};
  const std::vector<Vec3f> loose{{-0.4f, 0, 0}, {-0.1f, 0, 0}, {-0.3f, 0.4f, 0}, {-0.4f, 0, 0.2f}, {-0.1f, 0, 0.3f}, {-0.3f, 0.3f, 0.4f}};
  const int mixed = b.mesh({GltfBuilder::primitive(b.vectors(tetra, 16), b.indices(tetra_idx, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE), -1, green),
                            GltfBuilder::primitive(b.vectors(loose))},
                           "mixed");
  local.push_back(triangles_of(tetra, tetra_idx, TINYGLTF_MODE_TRIANGLES));
  for (const auto& t : triangles_of(loose, all(loose.size()), TINYGLTF_MODE_TRIANGLES)) local.back().push_back(t);
  // "strip": six vertices, u32 indices; "fan": five vertices, not indexed.
  const std::vector<Vec3f> strip{{0, 0, 0}, {0, 0.3f, 0}, {0.3f, 0, 0.05f}, {0.3f, 0.3f, 0.1f}, {0.6f, 0, 0}, {0.6f, 0.3f, 0.1f}};
  const std::vector<uint32_t> strip_idx{0, 1, 2, 3, 4, 5};
  const int strip_mesh = b.mesh({GltfBuilder::primitive(b.vectors(strip), b.indices(strip_idx, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT), -1, -1,
                                                        TINYGLTF_MODE_TRIANGLE_STRIP)},
                                "strip");
  local.push_back(triangles_of(strip, strip_idx, TINYGLTF_MODE_TRIANGLE_STRIP));
  const std::vector<Vec3f> fan{{0, 0, 0}, {0.4f, 0, 0}, {0.35f, 0.25f, 0}, {0.1f, 0.4f, 0.05f}, {-0.2f, 0.3f, 0}};
  const int fan_mesh = b.mesh({GltfBuilder::primitive(b.vectors(fan), -1, -1, red, TINYGLTF_MODE_TRIANGLE_FAN)}, "fan");
  local.push_back(triangles_of(fan, all(fan.size()), TINYGLTF_MODE_TRIANGLE_FAN));

  // Rotations as quaternions (x, y, z, w) about an axis.
  const auto turn = [](Vec3d axis, double degrees) {
    axis = normalize(axis);
    const double h = degrees * kPi / 360.0;
    return std::vector<double>{axis.x * std::sin(h), axis.y * std::sin(h), axis.z * std::sin(h), std::cos(h)};
  };
  const std::vector<double> t0{0.5, 0, -1}, r0 = turn({0, 1, 0}, 30), s0{1, 1, 1};
  const std::vector<double> t1{-1.5, 0.2, 0}, r1 = turn({1, 0, 0}, -20), s1{0.8, 0.8, 0.8};
  const Affine3d m2 = compose(node_transform({0.2, 0.9, 0.1}, turn({1, 1, 1}, 50), {}), node_transform({}, {}, {1.2, 0.7, 1.0}));
  const std::vector<double> t3{0.3, 0.4, 0.2}, s3{0.5, 1.5, 0.7};
  const std::vector<double> t4{2, -0.5, 0.5}, r4 = turn({0, 0, 1}, 45);
  const std::vector<double> t5{-0.5, -1, 0.3};
  const std::vector<double> t6{1, 1, 0}, s6{-1, 1, 1};
  const int n3 = b.node(mixed, t3, {}, s3);
  const int n1 = b.node(pair, t1, r1, s1);
  const int n2 = b.matrix_node(pair, column_major(m2), {n3});
  const int n5 = b.node(strip_mesh, t5);
  const int n0 = b.node(-1, t0, r0, s0, {n1, n2, n5});
  const int n4 = b.node(pair, t4, r4);
  const int n6 = b.node(fan_mesh, t6, {}, s6);
  b.scene({n0, n4, n6});

  HierarchyGltf out;
  const Affine3d a0 = node_transform(t0, r0, s0);
  const std::pair<int, Affine3d> placed[] = {
      {0, compose(a0, node_transform(t1, r1, s1))},
      {0, compose(a0, m2)},
      {1, compose(compose(a0, m2), node_transform(t3, {}, s3))},
      {0, node_transform(t4, r4, {})},
      {2, compose(a0, node_transform(t5, {}, {}))},
      {3, node_transform(t6, {}, s6)}};
  for (const auto& [mesh, to_world] : placed)
    for (const auto& t : local[size_t(mesh)])
      out.world_triangles.push_back({to_world.point(t[0]), to_world.point(t[1]), to_world.point(t[2])});
  out.model = std::move(b.model);
  return out;
}

/// A triangle with a perspective camera (a second camera node never used) and
/// KHR_lights_punctual point, directional and spot lights on nodes.
inline GltfBuilder camera_and_lights_gltf() {
  GltfBuilder b;
  const int mesh = b.mesh({GltfBuilder::primitive(b.vectors({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}))});
  tinygltf::Camera cam;
  cam.type = "perspective";
  cam.perspective.yfov = kPi / 4;
  cam.perspective.znear = 0.1;
  b.model.cameras.push_back(cam);
  tinygltf::Light point, sun, spot;
  point.type = "point";
  point.color = {1.0, 0.5, 0.25};
  point.intensity = 20.0;
  sun.type = "directional";
  sun.intensity = 3.0;
  spot.type = "spot";
  b.model.lights = {point, sun, spot};
  const auto light_node = [&](int light, std::vector<double> t, std::vector<double> q) {
    const int n = b.node(-1, std::move(t), std::move(q));
    tinygltf::Value::Object o;
    o["light"] = tinygltf::Value(light);
    b.model.nodes[size_t(n)].extensions["KHR_lights_punctual"] = tinygltf::Value(o);
    return n;
  };
  // The camera at (0, 0, 5) looking down its own -z; another camera node, never used.
  const int c0 = b.node(-1, {0, 0, 5});
  b.model.nodes[size_t(c0)].camera = 0;
  const int c1 = b.node(-1, {9, 9, 9});
  b.model.nodes[size_t(c1)].camera = 0;
  // The sun turned -90 degrees about x: its -z becomes -y, shining down.
  const double h = -kPi / 4;
  b.scene({b.node(mesh), c0, c1, light_node(0, {1, 2, 3}, {}), light_node(1, {}, {std::sin(h), 0, 0, std::cos(h)}),
           light_node(2, {0, 4, 0}, {})});
  b.model.extensionsUsed.push_back("KHR_lights_punctual");
  return b;
}

/// A valid file of one indexed triangle (u16 indices), to break.
inline GltfBuilder one_triangle() {
  GltfBuilder b;
  const int pos = b.vectors({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
  const int idx = b.indices({0, 1, 2}, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT);
  b.scene({b.node(b.mesh({GltfBuilder::primitive(pos, idx)}))});
  return b;
}

/// A file the tests write: `name` (with its extension), its model and form, and what is done
/// to it after writing (a JSON edit, or the file cut to `keep` bytes).
struct GltfCase {
  std::string name;
  tinygltf::Model model;
  GltfForm form = GltfForm::embedded;
  std::function<void(nlohmann::json&)> patch;
  size_t keep = 0;  ///< > 0: the written file cut to this many bytes
};

/// Writes `c` into folder `dir`; returns its path.
inline std::string write_case(const GltfCase& c, const std::string& dir) {
  const std::string path = dir + "/" + c.name;
  write_gltf(c.model, path, c.form, c.patch);
  if (c.keep > 0) {
    std::ifstream in(path, std::ios::binary);
    const std::string bytes(std::istreambuf_iterator<char>(in), {});
    std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes.substr(0, c.keep);
  }
  return path;
}

/// "../" enough times to reach the root from any folder a test or fuzzer writes in.
inline std::string to_root() {
  std::string up;
  for (int i = 0; i < 32; ++i) up += "../";
  return up;
}

/// The hostile files of issue 21 and the other refusals of the reader, each a small change of
/// one_triangle() (tests/loaders/gltf_test.cpp holds each one's message; the fuzz corpus
/// holds them all, tests/fuzz/make_gltf_corpus.cpp): "folder.bin" must be a directory beside
/// bad-directory-uri.gltf.
inline std::vector<GltfCase> hostile_gltf_cases() {
  std::vector<GltfCase> cases;
  const auto add = [&](std::string name, const std::function<void(GltfBuilder&)>& change,
                       std::function<void(nlohmann::json&)> patch = {}) {
    GltfBuilder b = one_triangle();
    change(b);
    cases.push_back({std::move(name), std::move(b.model), GltfForm::embedded, std::move(patch), 0});
  };
  const auto uri = [](std::string u) { return [u](nlohmann::json& doc) { doc["buffers"][0]["uri"] = u; }; };
  const auto same = [](GltfBuilder&) {};
  cases.push_back({"bad-truncated.glb", one_triangle().model, GltfForm::binary, {}, 90});
  add("bad-offset.gltf", [](GltfBuilder& b) { b.model.accessors[0].byteOffset = 8; });
  add("bad-stride.gltf", [](GltfBuilder& b) { b.model.bufferViews[0].byteStride = 8; });
  add("bad-count.gltf", [](GltfBuilder& b) { b.model.accessors[0].count = 4000000000u; });
  add("bad-view-length.gltf", [](GltfBuilder& b) { b.model.bufferViews[0].byteLength = 1000; });
  add("bad-index.gltf", [](GltfBuilder& b) {
    b.model.buffers[0].data[36 + 2] = 3;  // the second index (u16, little-endian) becomes 3 of 3 vertices
  });
  add("bad-cycle.gltf", [](GltfBuilder& b) {
    b.model.nodes[0].children = {1};
    b.node(-1, {}, {}, {}, {0});
  });
  add("bad-two-parents.gltf", [](GltfBuilder& b) {
    const int p = b.node(-1, {}, {}, {}, {0}), q = b.node(-1, {}, {}, {}, {0});
    b.model.scenes[0].nodes = {p, q};
  });
  add("bad-missing-buffer.gltf", same, uri("missing.bin"));
  add("bad-device-uri.gltf", same, uri(to_root() + "dev/zero"));
  add("bad-directory-uri.gltf", same, uri("folder.bin"));
  add("bad-sparse.gltf", same, [](nlohmann::json& doc) {
    doc["accessors"][0]["sparse"] = {{"count", 1},
                                     {"indices", {{"bufferView", 1}, {"componentType", 5123}}},
                                     {"values", {{"bufferView", 0}}}};
  });
  add("bad-draco.gltf", [](GltfBuilder& b) {
    b.model.meshes[0].primitives[0].extensions["KHR_draco_mesh_compression"] = tinygltf::Value(tinygltf::Value::Object{});
    b.model.accessors[0].bufferView = -1;  // the data only in the extension
  });
  add("bad-required-draco.gltf", [](GltfBuilder& b) {
    b.model.extensionsUsed = {"KHR_draco_mesh_compression"};
    b.model.extensionsRequired = {"KHR_draco_mesh_compression"};
  });
  add("bad-matrix.gltf", [](GltfBuilder& b) { b.model.nodes[0].matrix = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0.5, 0, 0, 0, 1}; });
  add("bad-far.gltf", [](GltfBuilder& b) { b.model.nodes[0].translation = {2e9, 0, 0}; });
  add("bad-quaternion.gltf", [](GltfBuilder& b) { b.model.nodes[0].rotation = {0, 0, 0, 0}; });
  add("bad-deep.gltf", [](GltfBuilder& b) {
    tinygltf::Value v(1);
    for (int i = 0; i < 100; ++i) v = tinygltf::Value(tinygltf::Value::Array{v});
    b.model.nodes[0].extras = v;
  });
  add("bad-no-scene.gltf", [](GltfBuilder& b) {
    b.model.scenes.clear();
    b.model.defaultScene = -1;
  });
  add("bad-missing-node.gltf", [](GltfBuilder& b) { b.model.nodes[0].children = {7}; });
  add("bad-uri-outside.gltf", same, uri("../outside.bin"));
  add("bad-uri-encoded.gltf", same, uri("..%2Foutside.bin"));
  add("bad-translation-type.gltf", same, [](nlohmann::json& doc) { doc["nodes"][0]["translation"] = {"a", 0, 0}; });
  add("bad-scene-index.gltf", same, [](nlohmann::json& doc) { doc["scene"] = -2; });
  add("bad-negative-offset.gltf", same, [](nlohmann::json& doc) { doc["bufferViews"][1]["byteOffset"] = -4; });
  add(
      "bad-emissive-strength.gltf",
      [](GltfBuilder& b) {
        b.model.meshes[0].primitives[0].material = b.material({0.5f, 0.5f, 0.5f}, {1, 1, 1});
      },
      [](nlohmann::json& doc) {
        doc["materials"][0]["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"] = "x";
      });
  add("bad-rotation-overflow.gltf", [](GltfBuilder& b) { b.model.nodes[0].rotation = {1e300, 0, 0, 1e300}; });
  add("bad-index-max.gltf", [](GltfBuilder& b) {
    b.model.meshes[0].primitives[0].indices = b.indices({0, 0xFFFFFFFFu, 2}, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT);
  });
  add("bad-light-type.gltf", [](GltfBuilder& b) {
    tinygltf::Light area;
    area.type = "area";
    b.model.lights = {area};
    tinygltf::Value::Object o;
    o["light"] = tinygltf::Value(0);
    b.model.nodes[0].extensions["KHR_lights_punctual"] = tinygltf::Value(o);
    b.model.extensionsUsed.push_back("KHR_lights_punctual");
  });
  return cases;
}

/// The triangles as an OBJ file (each triangle its own three vertices, %.9g).
inline std::string obj_of(const std::vector<std::array<Vec3d, 3>>& triangles) {
  std::string text = "# the flattened glTF test scene\n";
  char line[128];
  for (const auto& t : triangles)
    for (const Vec3d& v : t) {
      std::snprintf(line, sizeof line, "v %.9g %.9g %.9g\n", double(float(v.x)), double(float(v.y)), double(float(v.z)));
      text += line;
    }
  for (size_t i = 0; i < triangles.size(); ++i) text += "f " + std::to_string(3 * i + 1) + " " + std::to_string(3 * i + 2) + " " + std::to_string(3 * i + 3) + "\n";
  return text;
}

}  // namespace rp::test
