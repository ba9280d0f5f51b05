/// The glTF JSON check (io/loaders/gltf_check.h): types, ranges and indices of the values
/// the reader uses, buffer URIs confined to the glTF's folder, and the memory tinygltf would
/// take for the objects the JSON lists. Over 600 lines as one class on purpose: every section's
/// check names the others' sizes (an index into nodes, accessors, samplers) through the one
/// set of Section counts and helpers, which a split by section would have to pass around.

#include "io/loaders/gltf_check.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "base/error.h"
#include "base/text.h"
#include "io/loaders/tinygltf_config.h"

namespace rp {
namespace {

/// `uri` decoded as tinygltf 2.7 decodes a buffer's URI before opening it (dlib::urldecode):
/// "%XY" becomes the byte XY (a digit that is not hex counting as 0) and '+' a space.
std::string url_decoded(const std::string& uri) {
  const auto hex = [](char c) {
    return c >= '0' && c <= '9'   ? c - '0'
           : c >= 'a' && c <= 'f' ? c - 'a' + 10
           : c >= 'A' && c <= 'F' ? c - 'A' + 10
                                  : 0;
  };
  std::string out;
  for (size_t i = 0; i < uri.size(); ++i) {
    if (uri[i] == '+') {
      out += ' ';
    } else if (uri[i] == '%' && uri.size() > i + 2) {
      out += char(hex(uri[i + 1]) * 16 + hex(uri[i + 2]));
      i += 2;
    } else {
      out += uri[i];
    }
  }
  return out;
}

/// `folder` joined with `name` as tinygltf joins them (one '/' between).
std::string joined(const std::string& folder, const std::string& name) {
  return folder.empty() ? name : folder.back() == '/' ? folder + name : folder + "/" + name;
}

/// realpath(3) of `path`: absolute, every symbolic link followed; empty when it cannot be
/// resolved (errno says why).
std::string real_path(const std::string& path) {
  char* r = ::realpath(path.c_str(), nullptr);
  if (!r) return {};
  std::string out(r);
  std::free(r);
  return out;
}

/// Whether absolute `path` is `folder` (absolute, canonical) or lies below it.
bool lies_in(const std::string& path, const std::string& folder) {
  if (folder == "/") return path.starts_with('/');
  return path.starts_with(folder) && (path.size() == folder.size() || path[folder.size()] == '/');
}

/// The glTF JSON document, checked before tinygltf reads it: every value of the sections the
/// reader uses has the type glTF 2.0 gives it and lies in its range, and every index names an
/// element that exists. tinygltf 2.7 cannot be trusted with them: a value of the wrong type
/// becomes the default without a word (a translation ["a", 0, 0] is none, a negative
/// byteOffset is 0, "scene": -2 is no default scene), an index is cut to int, a GLB buffer of
/// byteLength 0 throws std::out_of_range, and what it refuses it names without a JSON path.
/// Each refusal throws one line naming the file and the JSON path of the value.
///
/// It also resolves every external buffer (a URI that is not a data URI): decoded as tinygltf
/// decodes it, the path must lie in the glTF's folder or below, both as written (a URI is
/// relative: "../x.bin" and "/x.bin" are refused, "sub/../x.bin" is read) and, when the file
/// exists, with every symbolic link followed (realpath(3), against the folder's own canonical
/// path): a link inside the folder to a file outside is refused. A link swapped in between this
/// check and the read is not caught.
///
/// First of all, once the sections are known to be arrays of objects, it refuses objects that
/// would make tinygltf take more memory than the input allows (memory(): gltf_check.h states
/// the rule, the top of gltf.cpp its reasons).
class JsonCheck {
 public:
  using json = nlohmann::json;

  JsonCheck(const GltfSource& source, const json& doc)
      : file_(source.path),
        doc_(doc),
        binary_(source.binary),
        bin_bytes_(source.bin_bytes),
        base_(source.base),
        file_bytes_(source.file_bytes),
        json_bytes_(source.json_bytes) {}

  /// Checks the document; returns its external buffers, in order.
  std::vector<GltfBufferFile> run() {
    if (!doc_.is_object()) fail("$", cat(shown(doc_), " is not a JSON object"));
    const json* asset = object(doc_, "$", "asset");
    if (!asset) fail("$", "has no \"asset\"");
    string(*asset, "$.asset", "version", true);
    for (const char* key : {"extensionsUsed", "extensionsRequired"})
      if (const json* a = find(doc_, key)) {
        if (!a->is_array()) fail(cat("$.", key), cat(shown(*a), " is not an array"));
        for (size_t i = 0; i < a->size(); ++i)
          if (!(*a)[i].is_string()) fail(cat("$.", key, "[", i, "]"), cat(shown((*a)[i]), " is not a string"));
      }
    for (const char* key : {"images", "textures", "samplers"}) objects(doc_, "$", key);
    const json& animations = objects(doc_, "$", "animations");
    const json& scenes = objects(doc_, "$", "scenes");
    const json& nodes = objects(doc_, "$", "nodes");
    const json& meshes = objects(doc_, "$", "meshes");
    const json& accessors = objects(doc_, "$", "accessors");
    const json& views = objects(doc_, "$", "bufferViews");
    const json& buffers = objects(doc_, "$", "buffers");
    const json& materials = objects(doc_, "$", "materials");
    const json& cameras = objects(doc_, "$", "cameras");
    const json* lights_ext = nullptr;
    if (const json* e = object(doc_, "$", "extensions")) lights_ext = object(*e, "$.extensions", "KHR_lights_punctual");
    const std::string lp = "$.extensions.KHR_lights_punctual";
    const json& lights = lights_ext ? objects(*lights_ext, lp, "lights") : none_;
    scene_ = {"scene", "scenes", scenes.size()};
    node_ = {"node", "nodes", nodes.size()};
    mesh_ = {"mesh", "meshes", meshes.size()};
    accessor_ = {"accessor", "accessors", accessors.size()};
    view_ = {"bufferView", "bufferViews", views.size()};
    buffer_ = {"buffer", "buffers", buffers.size()};
    material_ = {"material", "materials", materials.size()};
    camera_ = {"camera", "cameras", cameras.size()};
    light_ = {"light", "lights", lights.size()};
    skin_ = {"skin", "skins", objects(doc_, "$", "skins").size()};
    memory(meshes, buffers, lp);

    index(doc_, "$", "scene", scene_);
    for (size_t i = 0; i < scenes.size(); ++i) indices(scenes[i], cat("$.scenes[", i, "]"), "nodes", node_);
    for (size_t i = 0; i < nodes.size(); ++i) node(nodes[i], cat("$.nodes[", i, "]"));
    for (size_t i = 0; i < meshes.size(); ++i) mesh(meshes[i], cat("$.meshes[", i, "]"));
    for (size_t i = 0; i < accessors.size(); ++i) accessor(accessors[i], cat("$.accessors[", i, "]"));
    for (size_t i = 0; i < views.size(); ++i) buffer_view(views[i], cat("$.bufferViews[", i, "]"));
    for (size_t i = 0; i < materials.size(); ++i) material(materials[i], cat("$.materials[", i, "]"));
    for (size_t i = 0; i < cameras.size(); ++i) camera(cameras[i], cat("$.cameras[", i, "]"));
    for (size_t i = 0; i < lights.size(); ++i) light(lights[i], cat(lp, ".lights[", i, "]"));
    for (size_t i = 0; i < animations.size(); ++i) animation(animations[i], cat("$.animations[", i, "]"));
    std::vector<GltfBufferFile> external;
    for (size_t i = 0; i < buffers.size(); ++i)
      if (std::optional<GltfBufferFile> b = buffer(buffers[i], i)) external.push_back(std::move(*b));
    return external;
  }

 private:
  /// An array of the document that indices name: its element's name, its own, its size.
  struct Section {
    const char* noun = "";
    const char* plural = "";
    size_t count = 0;
  };
  /// The numbers a value may take: [lo, hi], or (lo, hi] when `open_low`; `text` says so.
  struct Range {
    double lo, hi;
    bool open_low;
    const char* text;
  };
  static constexpr double kInf = std::numeric_limits<double>::infinity();
  static constexpr Range kAny{-kInf, kInf, false, ""};
  static constexpr Range kNonNegative{0.0, kInf, false, " >= 0"};
  static constexpr Range kPositive{0.0, kInf, true, " > 0"};
  static constexpr Range kUnitInterval{0.0, 1.0, false, " in [0, 1]"};

  [[noreturn]] void fail(const std::string& path, const std::string& what) const {
    throw Error(cat(file_, ": ", path, ": ", what));
  }

  /// A value as a message quotes it: a number, string or literal as JSON writes it (cut, made
  /// printable), an array or object by its kind.
  static std::string shown(const json& v) {
    if (v.is_array()) return "an array";
    if (v.is_object()) return "an object";
    return printable(v.dump());
  }

  static const json* find(const json& o, const char* key) {
    const auto it = o.find(key);
    return it == o.end() ? nullptr : &*it;
  }

  /// Object `key` of `o` (at `path`); nothing when absent.
  const json* object(const json& o, const std::string& path, const char* key) const {
    const json* v = find(o, key);
    if (v && !v->is_object()) fail(cat(path, ".", key), cat(shown(*v), " is not an object"));
    return v;
  }

  /// Array `key` of `o` (at `path`), each element an object; an empty array when absent.
  const json& objects(const json& o, const std::string& path, const char* key) const {
    const json* a = find(o, key);
    if (!a) return none_;
    const std::string p = cat(path, ".", key);
    if (!a->is_array()) fail(p, cat(shown(*a), " is not an array"));
    for (size_t i = 0; i < a->size(); ++i)
      if (!(*a)[i].is_object()) fail(cat(p, "[", i, "]"), cat(shown((*a)[i]), " is not an object"));
    return *a;
  }

  /// An integer value (a number written with a fraction or exponent is not one); an unsigned
  /// one beyond int64 as int64's largest, outside every range here.
  static std::optional<int64_t> integer(const json& v) {
    if (v.is_number_unsigned()) return int64_t(std::min<uint64_t>(v.get<uint64_t>(), uint64_t(INT64_MAX)));
    if (v.is_number_integer()) return v.get<int64_t>();
    return std::nullopt;
  }

  /// Integer `key` of `o` (at `path`) in [lo, hi]; `fallback` when absent and not required.
  int64_t integer(const json& o, const std::string& path, const char* key, int64_t lo, int64_t hi, bool required,
                  int64_t fallback = 0) const {
    const json* v = find(o, key);
    if (!v) {
      if (required) fail(path, cat("has no \"", key, "\""));
      return fallback;
    }
    const std::optional<int64_t> n = integer(*v);
    if (!n || *n < lo || *n > hi)
      fail(cat(path, ".", key),
           cat(shown(*v), " is not an integer ", hi == INT64_MAX ? cat(">= ", lo) : cat("in [", lo, ", ", hi, "]")));
    return *n;
  }

  /// Value `v` (at `path`) an index into `s`.
  void index_value(const json& v, const std::string& path, const Section& s) const {
    const std::optional<int64_t> n = integer(v);
    if (!n) fail(path, cat(shown(v), " is not an index (an integer >= 0)"));
    if (*n < 0 || uint64_t(*n) >= s.count) fail(path, cat(*n, " names no ", s.noun, " (", s.count, " ", s.plural, ")"));
  }

  /// Index `key` of `o` (at `path`) into `s`, when present (or `required`).
  void index(const json& o, const std::string& path, const char* key, const Section& s, bool required = false) const {
    if (const json* v = find(o, key)) {
      index_value(*v, cat(path, ".", key), s);
    } else if (required) {
      fail(path, cat("has no \"", key, "\""));
    }
  }

  /// Array `key` of `o` (at `path`) of indices into `s`, when present.
  void indices(const json& o, const std::string& path, const char* key, const Section& s) const {
    const json* a = find(o, key);
    if (!a) return;
    const std::string p = cat(path, ".", key);
    if (!a->is_array()) fail(p, cat(shown(*a), " is not an array of ", s.noun, " indices"));
    for (size_t i = 0; i < a->size(); ++i) index_value((*a)[i], cat(p, "[", i, "]"), s);
  }

  /// Value `v` (at `path`) a finite number in `r`.
  double number(const json& v, const std::string& path, const Range& r) const {
    if (!v.is_number()) fail(path, cat(shown(v), " is not a number", r.text));
    const double x = v.get<double>();
    if (!std::isfinite(x)) fail(path, "not a finite number");
    if (x < r.lo || x > r.hi || (r.open_low && x == r.lo)) fail(path, cat(shown(v), " is not a number", r.text));
    return x;
  }

  /// Number `key` of `o` (at `path`) in `r`, when present (or `required`).
  void number(const json& o, const std::string& path, const char* key, const Range& r, bool required = false) const {
    if (const json* v = find(o, key)) {
      number(*v, cat(path, ".", key), r);
    } else if (required) {
      fail(path, cat("has no \"", key, "\""));
    }
  }

  /// Array `key` of `o` (at `path`): `n` numbers in `r`; empty when absent.
  std::vector<double> numbers(const json& o, const std::string& path, const char* key, size_t n, const Range& r) const {
    const json* a = find(o, key);
    if (!a) return {};
    const std::string p = cat(path, ".", key);
    if (!a->is_array()) fail(p, cat(shown(*a), " is not an array of ", n, " numbers"));
    if (a->size() != n) fail(p, cat(a->size(), " numbers, not ", n));
    std::vector<double> out;
    for (size_t i = 0; i < n; ++i) out.push_back(number((*a)[i], cat(p, "[", i, "]"), r));
    return out;
  }

  /// String `key` of `o` (at `path`), one of `allowed` (`what` names them) when given; nothing
  /// when absent and not required.
  std::optional<std::string> string(const json& o, const std::string& path, const char* key, bool required,
                                    std::initializer_list<std::string_view> allowed = {}, const char* what = "") const {
    const json* v = find(o, key);
    if (!v) {
      if (required) fail(path, cat("has no \"", key, "\""));
      return std::nullopt;
    }
    const std::string p = cat(path, ".", key);
    if (!v->is_string()) fail(p, cat(shown(*v), " is not a string"));
    std::string s = v->get<std::string>();
    if (allowed.size() && std::find(allowed.begin(), allowed.end(), s) == allowed.end()) {
      std::string list;
      for (std::string_view a : allowed) list += cat(list.empty() ? "" : ", ", a);
      fail(p, cat(gltf_quoted(s), " is not ", what, " (", list, ")"));
    }
    return s;
  }

  /// Array `key` of `o` (at `path`) of any number of finite numbers (morph target weights),
  /// when present.
  void weights(const json& o, const std::string& path, const char* key) const {
    const json* a = find(o, key);
    if (!a) return;
    const std::string p = cat(path, ".", key);
    if (!a->is_array()) fail(p, cat(shown(*a), " is not an array of numbers"));
    for (size_t i = 0; i < a->size(); ++i) number((*a)[i], cat(p, "[", i, "]"), kAny);
  }

  void node(const json& n, const std::string& path) const {
    indices(n, path, "children", node_);
    index(n, path, "mesh", mesh_);
    index(n, path, "camera", camera_);
    index(n, path, "skin", skin_);
    numbers(n, path, "matrix", 16, kAny);
    numbers(n, path, "translation", 3, kAny);
    numbers(n, path, "scale", 3, kAny);
    weights(n, path, "weights");
    const std::vector<double> q = numbers(n, path, "rotation", 4, kAny);
    if (!q.empty())
      if (const std::optional<std::string> problem = rotation_problem(q)) fail(path + ".rotation", *problem);
    if (const json* e = object(n, path, "extensions"))
      if (const json* l = object(*e, path + ".extensions", "KHR_lights_punctual"))
        index(*l, path + ".extensions.KHR_lights_punctual", "light", light_, true);
  }

  void mesh(const json& m, const std::string& path) const {
    if (!find(m, "primitives")) fail(path, "has no \"primitives\"");
    const json& primitives = objects(m, path, "primitives");
    for (size_t k = 0; k < primitives.size(); ++k) {
      const json& p = primitives[k];
      const std::string pp = cat(path, ".primitives[", k, "]");
      const json* attributes = object(p, pp, "attributes");
      if (!attributes) fail(pp, "has no \"attributes\"");
      for (const auto& [name, v] : attributes->items())
        index_value(v, cat(pp, ".attributes.", printable(name)), accessor_);
      index(p, pp, "indices", accessor_);
      index(p, pp, "material", material_);
      integer(p, pp, "mode", 0, 6, false);
      const json& targets = objects(p, pp, "targets");
      for (size_t t = 0; t < targets.size(); ++t)
        for (const auto& [name, v] : targets[t].items())
          index_value(v, cat(pp, ".targets[", t, "].", printable(name)), accessor_);
    }
    weights(m, path, "weights");
  }

  /// An animation: its channels name a sampler of its own and a node, and a path glTF
  /// defines; its samplers name accessors and an interpolation glTF defines. tinygltf 2.7
  /// drops a channel without a target node or path without a word (the channels after it then
  /// move up), so both are required here; a target without a node (KHR_animation_pointer's)
  /// is refused with them.
  void animation(const json& a, const std::string& path) const {
    for (const char* key : {"channels", "samplers"})
      if (!find(a, key)) fail(path, cat("has no \"", key, "\""));
    const json& samplers = objects(a, path, "samplers");
    const Section sampler{"sampler", "samplers", samplers.size()};
    const json& channels = objects(a, path, "channels");
    for (size_t c = 0; c < channels.size(); ++c) {
      const std::string cp = cat(path, ".channels[", c, "]");
      index(channels[c], cp, "sampler", sampler, true);
      const json* target = object(channels[c], cp, "target");
      if (!target) fail(cp, "has no \"target\"");
      index(*target, cp + ".target", "node", node_, true);
      string(*target, cp + ".target", "path", true, {"translation", "rotation", "scale", "weights"},
             "an animation path");
    }
    for (size_t s = 0; s < samplers.size(); ++s) {
      const std::string sp = cat(path, ".samplers[", s, "]");
      index(samplers[s], sp, "input", accessor_, true);
      index(samplers[s], sp, "output", accessor_, true);
      string(samplers[s], sp, "interpolation", false, {"LINEAR", "STEP", "CUBICSPLINE"}, "an interpolation");
    }
  }

  void accessor(const json& a, const std::string& path) const {
    index(a, path, "bufferView", view_);
    integer(a, path, "byteOffset", 0, INT64_MAX, false);
    if (!find(a, "componentType")) fail(path, "has no \"componentType\"");
    const json& type = a["componentType"];
    static constexpr int64_t kTypes[] = {5120, 5121, 5122, 5123, 5125, 5126};
    const std::optional<int64_t> t = integer(type);
    if (!t || std::find(std::begin(kTypes), std::end(kTypes), *t) == std::end(kTypes))
      fail(path + ".componentType", cat(shown(type), " is not a componentType (5120, 5121, 5122, 5123, 5125, 5126)"));
    integer(a, path, "count", 1, INT64_MAX, true);
    string(a, path, "type", true, {"SCALAR", "VEC2", "VEC3", "VEC4", "MAT2", "MAT3", "MAT4"}, "an accessor type");
    if (const json* n = find(a, "normalized"); n && !n->is_boolean())
      fail(path + ".normalized", cat(shown(*n), " is not true or false"));
  }

  void buffer_view(const json& v, const std::string& path) const {
    index(v, path, "buffer", buffer_, true);
    integer(v, path, "byteOffset", 0, INT64_MAX, false);
    integer(v, path, "byteLength", 1, INT64_MAX, true);
    if (const json* s = find(v, "byteStride")) {
      const std::optional<int64_t> n = integer(*s);
      if (!n || *n < 4 || *n > 252 || *n % 4)
        fail(path + ".byteStride", cat(shown(*s), " is not a byteStride (a multiple of 4 in [4, 252])"));
    }
  }

  /// Buffer i: its data in the GLB's BIN chunk, a data URI, or a file (returned).
  std::optional<GltfBufferFile> buffer(const json& b, size_t i) const {
    const std::string path = cat("$.buffers[", i, "]");
    const int64_t length = integer(b, path, "byteLength", 1, INT64_MAX, true);
    const std::optional<std::string> uri = string(b, path, "uri", false);
    if (!uri || uri->empty()) {
      if (!binary_) fail(path, "has no \"uri\" (a .gltf's buffer names its data)");
      if (i != 0) fail(path, "has no \"uri\" (only buffer 0 of a GLB is its BIN chunk)");
      if (!bin_bytes_) fail(path, "has no \"uri\", and the GLB has no BIN chunk");
      if (uint64_t(length) > *bin_bytes_)
        fail(path + ".byteLength", cat(length, " bytes, more than the GLB's BIN chunk holds (", *bin_bytes_, ")"));
      return std::nullopt;
    }
    if (tinygltf::IsDataURI(*uri)) return std::nullopt;
    const std::string decoded = url_decoded(*uri);
    return GltfBufferFile{i, *uri, joined(base_, decoded), confined(*uri, decoded, path + ".uri"), uint64_t(length)};
  }

  /// The file to read for URI `uri` (at `path`; `decoded` as tinygltf decodes it), after
  /// checking that it lies in the glTF's folder: the folder joined with the URI, its "." and
  /// ".." segments removed (as RFC 3986 resolves a relative reference).
  std::string confined(const std::string& uri, const std::string& decoded, const std::string& path) const {
    const std::string shown_uri =
        decoded == uri ? gltf_quoted(uri) : cat(gltf_quoted(uri), " (", gltf_quoted(decoded), " decoded)");
    if (decoded.find('\0') != std::string::npos) fail(path, cat(shown_uri, " holds a NUL byte"));
    const std::string outside = cat(shown_uri, " lies outside the glTF's folder");
    if (decoded.starts_with('/')) fail(path, outside);
    if (folder_.empty()) {
      folder_ = real_path(base_);
      if (folder_.empty()) fail(path, cat("the glTF's folder cannot be resolved: ", std::strerror(errno)));
    }
    namespace fs = std::filesystem;
    std::string lexical = (fs::path(folder_) / decoded).lexically_normal().string();
    while (lexical.size() > 1 && lexical.back() == '/') lexical.pop_back();
    if (!lies_in(lexical, folder_)) fail(path, outside);
    const std::string file = (fs::path(base_) / decoded).lexically_normal().string();
    const std::string real = real_path(file);  // nothing when it does not exist: reading says so
    if (!real.empty() && !lies_in(real, folder_)) fail(path, outside + " once symbolic links are followed");
    return file;
  }

  void material(const json& m, const std::string& path) const {
    if (const json* pbr = object(m, path, "pbrMetallicRoughness")) {
      const std::string pp = path + ".pbrMetallicRoughness";
      numbers(*pbr, pp, "baseColorFactor", 4, kUnitInterval);
      number(*pbr, pp, "metallicFactor", kUnitInterval);
      number(*pbr, pp, "roughnessFactor", kUnitInterval);
    }
    numbers(m, path, "emissiveFactor", 3, kUnitInterval);
    string(m, path, "alphaMode", false, {"OPAQUE", "MASK", "BLEND"}, "an alphaMode");
    number(m, path, "alphaCutoff", kNonNegative);
    if (const json* e = object(m, path, "extensions"))
      if (const json* s = object(*e, path + ".extensions", "KHR_materials_emissive_strength"))
        number(*s, path + ".extensions.KHR_materials_emissive_strength", "emissiveStrength", kNonNegative);
  }

  void camera(const json& c, const std::string& path) const {
    const std::string type = *string(c, path, "type", true, {"perspective", "orthographic"}, "a camera type");
    const json* p = object(c, path, type.c_str());
    if (!p) fail(path, cat("has no \"", type, "\""));
    const std::string pp = cat(path, ".", type);
    if (type == "perspective") {
      // Unused by raypack, znear, zfar and aspectRatio may be 0: tinygltf's writer writes 0
      // for each it was not given.
      number(*p, pp, "yfov", kPositive, true);
      number(*p, pp, "znear", kNonNegative, true);
      number(*p, pp, "zfar", kNonNegative);
      number(*p, pp, "aspectRatio", kNonNegative);
    } else {
      number(*p, pp, "xmag", kAny, true);
      number(*p, pp, "ymag", kAny, true);
      number(*p, pp, "zfar", kNonNegative, true);
      number(*p, pp, "znear", kNonNegative, true);
    }
  }

  void light(const json& l, const std::string& path) const {
    string(l, path, "type", true, {"directional", "point", "spot"}, "a KHR_lights_punctual type");
    numbers(l, path, "color", 3, kNonNegative);
    number(l, path, "intensity", kNonNegative);
    number(l, path, "range", kPositive);
    if (const json* s = object(l, path, "spot")) {
      number(*s, path + ".spot", "innerConeAngle", kNonNegative);
      number(*s, path + ".spot", "outerConeAngle", kNonNegative);
    }
  }

  /// One kind of object tinygltf builds: where the JSON lists them, what they are called, how
  /// many there are and the bytes of one in tinygltf.
  struct Kind {
    std::string path;
    const char* plural;
    uint64_t count;
    uint64_t bytes;
  };

  /// The size of array `key` of `o`; 0 when it is absent or not an array (tinygltf refuses
  /// that itself).
  static uint64_t size_of(const json& o, const char* key) {
    const json* a = find(o, key);
    return a && a->is_array() ? a->size() : 0;
  }

  /// The values of `v` that tinygltf keeps as a tinygltf::Value: every value at or below an
  /// "extras" or "extensions" member (`inside`: `v` is one). Recursive: the JSON's depth is
  /// at most 64 (checked before it was parsed).
  static uint64_t kept_values(const json& v, bool inside) {
    uint64_t n = inside ? 1 : 0;
    if (v.is_object()) {
      for (auto it = v.begin(); it != v.end(); ++it)
        n += kept_values(*it, inside || it.key() == "extras" || it.key() == "extensions");
    } else if (v.is_array()) {
      for (const json& e : v) n += kept_values(e, inside);
    }
    return n;
  }

  /// "640 MiB", "1.1 GiB".
  static std::string memory_text(uint64_t bytes) {
    char text[32];
    if (bytes < (uint64_t(1) << 30)) {
      std::snprintf(text, sizeof text, "%.0f MiB", double(bytes) / double(uint64_t(1) << 20));
    } else {
      std::snprintf(text, sizeof text, "%.1f GiB", double(bytes) / double(uint64_t(1) << 30));
    }
    return text;
  }

  /// Refuses a document whose objects would make tinygltf take more memory than its input
  /// allows (gltf_check.h states the rule), naming the kind that takes the most. Run before
  /// the elements are checked one by one, so that a refusal costs no time per element.
  void memory(const json& meshes, const json& buffers, const std::string& lights_path) const {
    uint64_t primitives = 0, channels = 0, animation_samplers = 0;
    for (const json& m : meshes) primitives += size_of(m, "primitives");
    const json& animations = objects(doc_, "$", "animations");
    for (const json& a : animations) {
      channels += size_of(a, "channels");
      animation_samplers += size_of(a, "samplers");
    }
    const auto count = [&](const char* key) { return uint64_t(objects(doc_, "$", key).size()); };
    const Kind kinds[] = {
        {"$.scenes", "scenes", scene_.count, sizeof(tinygltf::Scene)},
        {"$.nodes", "nodes", node_.count, sizeof(tinygltf::Node)},
        {"$.meshes", "meshes", mesh_.count, sizeof(tinygltf::Mesh)},
        {"$.meshes", "primitives", primitives, sizeof(tinygltf::Primitive)},
        {"$.accessors", "accessors", accessor_.count, sizeof(tinygltf::Accessor)},
        {"$.bufferViews", "bufferViews", view_.count, sizeof(tinygltf::BufferView)},
        {"$.buffers", "buffers", buffer_.count, sizeof(tinygltf::Buffer)},
        {"$.materials", "materials", material_.count, sizeof(tinygltf::Material)},
        {"$.cameras", "cameras", camera_.count, sizeof(tinygltf::Camera)},
        {lights_path + ".lights", "lights", light_.count, sizeof(tinygltf::Light)},
        {"$.images", "images", count("images"), sizeof(tinygltf::Image)},
        {"$.textures", "textures", count("textures"), sizeof(tinygltf::Texture)},
        {"$.samplers", "samplers", count("samplers"), sizeof(tinygltf::Sampler)},
        {"$.skins", "skins", count("skins"), sizeof(tinygltf::Skin)},
        {"$.animations", "animations", animations.size(), sizeof(tinygltf::Animation)},
        {"$.animations", "animation channels", channels, sizeof(tinygltf::AnimationChannel)},
        {"$.animations", "animation samplers", animation_samplers, sizeof(tinygltf::AnimationSampler)},
        {"$", "values in extras and extensions", kept_values(doc_, false), sizeof(tinygltf::Value)},
    };
    // No sum overflows: every count is below the JSON's 2^31 bytes, every size below 2^12.
    uint64_t estimate = kGltfDomBytesPerJsonByte * json_bytes_;
    const Kind* most = &kinds[0];
    for (const Kind& k : kinds) {
      estimate += k.count * k.bytes;
      if (k.count * k.bytes > most->count * most->bytes) most = &k;
    }
    // An external buffer counts as its byteLength, at most kMaxGltfBytes: tinygltf reads the
    // buffers before it builds any other object, and stops at a file of another size or
    // larger. Its entry is checked after this: a wrong one is refused before tinygltf runs.
    uint64_t input = file_bytes_;
    for (const json& b : buffers) {
      const json* uri = find(b, "uri");
      const json* length = find(b, "byteLength");
      if (!uri || !uri->is_string() || uri->get_ref<const std::string&>().empty() ||
          tinygltf::IsDataURI(uri->get_ref<const std::string&>()) || !length)
        continue;
      if (const std::optional<int64_t> n = integer(*length); n && *n > 0)
        input += std::min(uint64_t(*n), kMaxGltfBytes);
    }
    input = std::min(input, UINT64_MAX / kGltfMemoryPerInputByte);
    const uint64_t budget = std::max(kGltfMemoryFloor, input * kGltfMemoryPerInputByte);
    if (estimate > budget)
      fail(most->path,
           cat(most->count, " ", most->plural, " would make tinygltf take about ", memory_text(estimate),
               ", more than the ", memory_text(budget), " allowed for ", input, " bytes of input (",
               kGltfMemoryPerInputByte, " bytes per byte of input, at least ", memory_text(kGltfMemoryFloor), ")"));
  }

  const std::string& file_;
  const json& doc_;
  const bool binary_;
  const std::optional<uint64_t> bin_bytes_;
  const std::string& base_;
  const uint64_t file_bytes_;
  const uint64_t json_bytes_;
  mutable std::string folder_;  ///< realpath of base_, found on the first external buffer
  const json none_ = json::array();
  Section scene_, node_, mesh_, accessor_, view_, buffer_, material_, camera_, light_, skin_;
};

}  // namespace

std::vector<GltfBufferFile> check_gltf_json(const GltfSource& source, const nlohmann::json& doc) {
  return JsonCheck(source, doc).run();
}

std::optional<std::string> rotation_problem(std::span<const double> q) {
  double big = 0.0;
  for (double c : q) big = std::max(big, std::abs(c));
  if (big == 0.0) return "a zero quaternion is no rotation";
  double sum = 0.0;
  for (double c : q) sum += (c / big) * (c / big);
  const double length = big * std::sqrt(sum);
  if (!(std::abs(length - 1.0) <= kUnitQuaternionTolerance))
    return cat("its length ", length, " is not 1 (a rotation is a unit quaternion, within ", kUnitQuaternionTolerance,
               ")");
  return std::nullopt;
}

std::string gltf_quoted(std::string_view text) { return cat("\"", printable(text), "\""); }

}  // namespace rp
