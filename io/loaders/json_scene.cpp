/// JSON scene files: camera, materials, lights and objects (spheres, planes, polygons,
/// quadrics, meshes from OBJ/PLY files) in one document, parsed by nlohmann-json 3.11
/// (Debian 12's nlohmann-json3-dev). Everything is checked before it reaches the Scene; the
/// first problem throws one line, "<file>: <JSON path>: <what>", e.g.
///   scene.json: $.objects[2].radus: unknown key (expected one of: type, center, radius, material)
///
/// The format, key by key, with every default, range and error message, is specified in
/// docs/scene-formats.md ("The JSON scene format, key by key"); this reader enforces it rule
/// by rule, and a change to either goes with a change to the other.

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

#include "base/error.h"
#include "base/text.h"
#include "io/input_file.h"
#include "io/json_text.h"
#include "io/loaders/load.h"
#include "io/memory_reserve.h"
#include "io/ordered_json.h"

namespace rp {
namespace {

/// ordered_json keeps the file's key order: material ids follow the file, and the first
/// unknown key reported is the first one in the file.
using Json = nlohmann::ordered_json;

constexpr size_t kShownChars = 40;
constexpr double kInf = std::numeric_limits<double>::infinity();

/// A value as the file has it, compact, at most kShownChars characters (cut with "...",
/// never inside a UTF-8 sequence).
std::string show(const Json& v) {
  std::string s = v.dump(-1, ' ', false, Json::error_handler_t::replace);
  if (s.size() <= kShownChars) return s;
  size_t n = kShownChars - 3;
  while (n > 0 && (static_cast<unsigned char>(s[n]) & 0xC0) == 0x80) --n;
  return s.substr(0, n) + "...";
}

/// JSONPath of member `key` of `path`: $.a.b, or $.a["my key"] when key is not an identifier.
std::string member(const std::string& path, std::string_view key) {
  const bool identifier =
      !key.empty() && !std::isdigit(static_cast<unsigned char>(key[0])) &&
      std::all_of(key.begin(), key.end(), [](unsigned char c) { return std::isalnum(c) != 0 || c == '_'; });
  if (identifier) return cat(path, ".", key);
  return cat(path, "[", show(Json(std::string(key))), "]");
}

std::string element(const std::string& path, size_t i) { return cat(path, "[", i, "]"); }

/// The names, comma-separated; past kShownNames of them, "and N more" (a message stays one
/// readable line whatever the file declares).
constexpr size_t kShownNames = 12;
std::string join(std::span<const std::string_view> names) {
  std::string out;
  for (size_t i = 0; i < names.size() && i < kShownNames; ++i) {
    if (!out.empty()) out += ", ";
    out += names[i];
  }
  if (names.size() > kShownNames) out += cat(" and ", names.size() - kShownNames, " more");
  return out;
}

/// A closed, open or half-open interval of accepted numbers, described as "> 0", ">= 1",
/// "in [0, 1]", "in (0, 180)".
struct Range {
  double lo = -kInf, hi = kInf;
  bool open_lo = false, open_hi = false;

  bool contains(double x) const { return (open_lo ? x > lo : x >= lo) && (open_hi ? x < hi : x <= hi); }
  std::string describe() const {
    if (lo > -kInf && hi < kInf) return cat("in ", open_lo ? "(" : "[", lo, ", ", hi, open_hi ? ")" : "]");
    if (lo > -kInf) return cat(open_lo ? "> " : ">= ", lo);
    return cat(open_hi ? "< " : "<= ", hi);
  }
};
constexpr Range kAnyNumber{};
constexpr Range kPositive{0.0, kInf, true, false};
constexpr Range kNonNegative{0.0, kInf, false, false};
constexpr Range kFraction{0.0, 1.0, false, false};
constexpr Range kFov{0.0, 180.0, true, true};
constexpr Range kIor{1.0, kInf, false, false};

constexpr std::string_view kTopKeys[] = {"camera", "materials", "meshes", "lights", "objects"};
constexpr std::string_view kCameraKeys[] = {"eye",         "look_at",  "up",           "fov", "model",
                                            "fisheye_fov", "aperture", "focus_distance"};
constexpr std::string_view kCameraModels[] = {"pinhole", "panoramic", "fisheye", "thin_lens"};
constexpr Range kFisheyeFov{0.0, 360.0, true, false};
constexpr std::string_view kMaterialKeys[] = {"diffuse", "specular", "shininess", "emission",
                                              "mirror",  "ior",      "opacity"};
constexpr std::string_view kLightTypes[] = {"point", "directional"};
constexpr std::string_view kPointLightKeys[] = {"type", "position", "intensity"};
constexpr std::string_view kDirectionalLightKeys[] = {"type", "direction", "irradiance"};
constexpr std::string_view kObjectTypes[] = {"sphere", "plane", "polygon", "quadric", "mesh", "instance"};
constexpr std::string_view kSphereKeys[] = {"type", "center", "radius", "material"};
constexpr std::string_view kPlaneKeys[] = {"type", "normal", "offset", "material"};
constexpr std::string_view kPolygonKeys[] = {"type", "vertices", "material"};
constexpr std::string_view kShapes[] = {"ellipsoid", "cylinder", "cone", "hyperboloid1", "hyperboloid2", "paraboloid"};
constexpr std::string_view kEllipsoidKeys[] = {"type", "shape", "center", "radii", "material"};
constexpr std::string_view kCylinderKeys[] = {"type",     "shape",       "center", "radius_a",
                                              "radius_b", "half_height", "axis",   "material"};
constexpr std::string_view kConeKeys[] = {"type", "shape", "center", "a", "b", "half_height", "axis", "material"};
constexpr std::string_view kHyperboloidKeys[] = {"type", "shape",       "center", "a",       "b",
                                                 "c",    "half_height", "axis",   "material"};
constexpr std::string_view kParaboloidKeys[] = {"type", "shape", "center", "a", "b", "height", "axis", "material"};
constexpr std::string_view kGeneralQuadricKeys[] = {"type", "coefficients", "center", "clip", "material"};
constexpr std::string_view kCoefficientKeys[] = {"A", "B", "C", "D", "E", "F", "G", "H", "I", "J"};
constexpr std::string_view kClipKeys[] = {"min", "max"};
constexpr std::string_view kAxes[] = {"x", "y", "z"};
constexpr std::string_view kMeshKeys[] = {"type", "file", "transform", "material"};
constexpr std::string_view kDeclaredMeshKeys[] = {"file", "material"};
constexpr std::string_view kInstanceKeys[] = {"type", "mesh", "transform"};
constexpr std::string_view kTransformKeys[] = {"scale", "rotate", "translate"};
constexpr std::string_view kRotateKeys[] = {"axis", "degrees"};

/// p -> rotation (scale * p) + translation, in double.
struct MeshTransform {
  Vec3d scale{1.0};
  std::array<Vec3d, 3> rotation{Vec3d(1, 0, 0), Vec3d(0, 1, 0), Vec3d(0, 0, 1)};  ///< rows
  Vec3d translation{0.0};

  Vec3d rotate(const Vec3d& v) const { return {dot(rotation[0], v), dot(rotation[1], v), dot(rotation[2], v)}; }
  Vec3f point(const Vec3f& p) const { return Vec3f(rotate(mul(Vec3d(p), scale)) + translation); }
  /// The inverse transpose of rotation * diag(scale) is rotation * diag(1 / scale).
  Vec3f normal(const Vec3f& n) const {
    const Vec3d s = Vec3d(n);
    return Vec3f(normalize(rotate({s.x / scale.x, s.y / scale.y, s.z / scale.z})));
  }
  /// The same map as an instance's placement (rounded to float).
  Affine3f affine() const {
    Affine3f a;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) a.m[i][j] = float(rotation[i][j] * scale[j]);
      a.m[i][3] = float(translation[i]);
    }
    return a;
  }
};

/// Rotation by `degrees` about unit `axis`, counter-clockwise seen from its tip (Rodrigues):
/// R = cos(a) I + sin(a) [axis]x + (1 - cos(a)) axis axis^T.
std::array<Vec3d, 3> rotation_matrix(const Vec3d& k, double degrees) {
  const double a = degrees * kPi / 180.0, c = std::cos(a), s = std::sin(a), t = 1.0 - c;
  return {Vec3d(c + t * k.x * k.x, t * k.x * k.y - s * k.z, t * k.x * k.z + s * k.y),
          Vec3d(t * k.x * k.y + s * k.z, c + t * k.y * k.y, t * k.y * k.z - s * k.x),
          Vec3d(t * k.x * k.z - s * k.y, t * k.y * k.z + s * k.x, c + t * k.z * k.z)};
}

/// Reads one parsed document into a Scene; every check names file_ and the JSON path.
class SceneReader {
 public:
  SceneReader(const std::string& file, Scene& scene) : file_(file), scene_(scene) {
    dir_ = std::filesystem::path(file).parent_path();
  }

  void read(const Json& root) {
    const std::string path = "$";
    object(root, path);
    check_keys(root, path, kTopKeys);
    if (const Json* m = find(root, "materials")) read_materials(*m, member(path, "materials"));
    if (const Json* c = find(root, "camera")) read_camera(*c, member(path, "camera"));
    if (const Json* l = find(root, "lights")) {
      const std::string lp = member(path, "lights");
      array(*l, lp);
      for (size_t i = 0; i < l->size(); ++i) read_light((*l)[i], element(lp, i));
    }
    if (const Json* m = find(root, "meshes")) read_declared_meshes(*m, member(path, "meshes"));
    const std::string op = member(path, "objects");
    const Json& objects = array(require(root, path, "objects"), op);
    if (objects.empty()) fail(op, cat("expected at least one object, got ", show(objects)));
    for (size_t i = 0; i < objects.size(); ++i) read_object(objects[i], element(op, i));
    place_declared_meshes();
  }

 private:
  [[noreturn]] void fail(const std::string& path, const std::string& what) const {
    throw Error(cat(file_, ": ", path, ": ", what));
  }

  /// Runs a Scene call, prefixing any error it throws with the file and `path`.
  template <typename F>
  void add(const std::string& path, F&& f) const {
    try {
      f();
    } catch (const Error& e) {
      fail(path, e.what());
    }
  }

  static const Json* find(const Json& obj, std::string_view key) {
    const auto it = obj.find(std::string(key));
    return it == obj.end() ? nullptr : &*it;
  }

  void check_keys(const Json& obj, const std::string& path, std::span<const std::string_view> keys) const {
    for (const auto& [key, value] : obj.items())
      if (std::find(keys.begin(), keys.end(), key) == keys.end())
        fail(member(path, key), cat("unknown key (expected one of: ", join(keys), ")"));
  }

  const Json& require(const Json& obj, const std::string& path, std::string_view key) const {
    const Json* v = find(obj, key);
    if (v == nullptr) fail(path, cat("missing key \"", key, "\""));
    return *v;
  }

  const Json& object(const Json& v, const std::string& path) const {
    if (!v.is_object()) fail(path, cat("expected an object, got ", show(v)));
    return v;
  }

  const Json& array(const Json& v, const std::string& path) const {
    if (!v.is_array()) fail(path, cat("expected an array, got ", show(v)));
    return v;
  }

  std::string string(const Json& v, const std::string& path) const {
    if (!v.is_string()) fail(path, cat("expected a string, got ", show(v)));
    return v.get<std::string>();
  }

  /// A number that fits in a float, checked against `range` as a float.
  float number(const Json& v, const std::string& path, const Range& range) const {
    if (!v.is_number()) fail(path, cat("expected a number, got ", show(v)));
    const float f = float(v.get<double>());
    if (!std::isfinite(f)) fail(path, cat(show(v), " is out of range (must fit in a 32-bit float)"));
    if (!range.contains(f)) fail(path, cat(show(v), " is out of range (must be ", range.describe(), ")"));
    return f;
  }

  float number(const Json& obj, const std::string& path, std::string_view key, float fallback,
               const Range& range) const {
    const Json* v = find(obj, key);
    return v == nullptr ? fallback : number(*v, member(path, key), range);
  }

  /// Exactly 3 numbers, each a float in `range`.
  Vec3f vector(const Json& v, const std::string& path, const Range& range = kAnyNumber) const {
    if (!v.is_array() || v.size() != 3 || !std::all_of(v.begin(), v.end(), [](const Json& x) { return x.is_number(); }))
      fail(path, cat("expected 3 numbers, got ", show(v)));
    return {number(v[0], element(path, 0), range), number(v[1], element(path, 1), range),
            number(v[2], element(path, 2), range)};
  }

  Vec3f vector(const Json& obj, const std::string& path, std::string_view key, const Vec3f& fallback,
               const Range& range = kAnyNumber) const {
    const Json* v = find(obj, key);
    return v == nullptr ? fallback : vector(*v, member(path, key), range);
  }

  Vec3f colour(const Json& obj, const std::string& path, std::string_view key, const Vec3f& fallback) const {
    return vector(obj, path, key, fallback, kNonNegative);
  }

  /// A vector of non-zero length, normalised (in double).
  Vec3d direction(const Json& obj, const std::string& path, std::string_view key, const Vec3d& fallback) const {
    const Json* v = find(obj, key);
    if (v == nullptr) return fallback;
    const std::string vp = member(path, key);
    const Vec3d d(vector(*v, vp));
    const double len = length(d);
    if (!(len > 0.0)) fail(vp, cat(show(*v), " is out of range (must have a non-zero length)"));
    return d / len;
  }

  /// Looks `v` (a string) up in `names`; fails with "unknown <what> "<v>" (expected one of: ...)".
  size_t choice(const Json& v, const std::string& path, std::string_view what,
                std::span<const std::string_view> names) const {
    const std::string s = string(v, path);
    const auto it = std::find(names.begin(), names.end(), s);
    if (it == names.end()) fail(path, cat("unknown ", what, " ", show(v), " (expected one of: ", join(names), ")"));
    return size_t(it - names.begin());
  }

  void read_materials(const Json& v, const std::string& path) {
    object(v, path);
    for (const auto& [name, value] : v.items()) {
      const std::string mp = member(path, name);
      object(value, mp);
      check_keys(value, mp, kMaterialKeys);
      Material m;
      m.name = name;
      m.diffuse = colour(value, mp, "diffuse", m.diffuse);
      m.specular = colour(value, mp, "specular", m.specular);
      m.shininess = number(value, mp, "shininess", m.shininess, kNonNegative);
      m.emission = colour(value, mp, "emission", m.emission);
      m.mirror = number(value, mp, "mirror", m.mirror, kFraction);
      m.ior = number(value, mp, "ior", m.ior, kIor);
      m.opacity = number(value, mp, "opacity", m.opacity, kFraction);
      uint32_t id = 0;
      add(mp, [&] { id = scene_.add_material(std::move(m)); });
      materials_.emplace_back(name, id);
      material_ids_.emplace(name, id);
    }
  }

  /// The material named by obj["material"], or material 0 when there is none.
  uint32_t material(const Json& obj, const std::string& path) const {
    const Json* v = find(obj, "material");
    if (v == nullptr) return 0;
    const std::string mp = member(path, "material");
    const std::string name = string(*v, mp);
    if (const auto it = material_ids_.find(name); it != material_ids_.end()) return it->second;
    std::vector<std::string_view> names;
    for (const auto& entry : materials_) names.push_back(entry.first);
    fail(mp, cat("unknown material ", show(*v), " (",
                 names.empty() ? std::string("no materials are defined") : "materials: " + join(names), ")"));
  }

  void read_camera(const Json& v, const std::string& path) {
    object(v, path);
    check_keys(v, path, kCameraKeys);
    CameraDesc c;
    c.eye = vector(v, path, "eye", c.eye);
    c.look_at = vector(v, path, "look_at", c.look_at);
    c.up = vector(v, path, "up", c.up);
    c.vfov_degrees = number(v, path, "fov", c.vfov_degrees, kFov);
    if (const Json* m = find(v, "model"))
      c.model = CameraModel(choice(*m, member(path, "model"), "camera model", kCameraModels));
    c.fisheye_fov_degrees = number(v, path, "fisheye_fov", c.fisheye_fov_degrees, kFisheyeFov);
    c.aperture = number(v, path, "aperture", c.aperture, kNonNegative);
    c.focus_distance = number(v, path, "focus_distance", c.focus_distance, kNonNegative);
    // The placement checks of Camera's constructor (render/camera.cpp), in the same float arithmetic.
    for (const char* key : {"eye", "look_at"}) {
      const Json* p = find(v, key);
      if (p != nullptr && !in_coordinate_range(key[0] == 'e' ? c.eye : c.look_at))
        fail(member(path, key), cat(show(*p), " is out of range (must be within the supported coordinate range |x| <= "
                                              "1073741824 = 2^30)"));
    }
    if (c.model == CameraModel::thin_lens && !in_coordinate_range(abs(c.eye) + Vec3f(c.aperture)))
      fail(member(path, "aperture"), cat(show(*find(v, "aperture")), " is out of range (the lens must stay within the "
                                                                       "supported coordinate range |x| <= 1073741824 = 2^30)"));
    if (!(c.focus_distance <= kMaxDirection))
      fail(member(path, "focus_distance"), cat(show(*find(v, "focus_distance")), " is out of range (must be <= 2147483648)"));
    const Vec3f view = c.look_at - c.eye;
    if (!(length(view) > 0.0f)) {
      const bool at = find(v, "look_at") != nullptr;
      const Json* shown = find(v, at ? "look_at" : "eye");
      fail(member(path, at ? "look_at" : "eye"),
           cat(shown != nullptr ? show(*shown) : std::string("[0,0,0]"), " is out of range (must differ from ",
               at ? "eye" : "look_at", ")"));
    }
    if (!(length(cross(normalize(view), c.up)) > 1e-6f * length(c.up))) {
      const Json* up = find(v, "up");
      fail(member(path, "up"), cat(up != nullptr ? show(*up) : std::string("[0,1,0]"),
                                   " is out of range (must not be parallel to look_at - eye)"));
    }
    scene_.set_camera(c);
  }

  void read_light(const Json& v, const std::string& path) {
    object(v, path);
    const size_t type = choice(require(v, path, "type"), member(path, "type"), "light type", kLightTypes);
    if (type == 0) {
      check_keys(v, path, kPointLightKeys);
      PointLight l;
      l.position = vector(require(v, path, "position"), member(path, "position"));
      l.intensity = colour(v, path, "intensity", l.intensity);
      add(path, [&] { scene_.add_light(l); });
    } else {
      check_keys(v, path, kDirectionalLightKeys);
      DirectionalLight l;
      l.direction = Vec3f(direction(v, path, "direction", Vec3d(l.direction)));
      l.irradiance = colour(v, path, "irradiance", l.irradiance);
      add(path, [&] { scene_.add_light(l); });
    }
  }

  void read_object(const Json& v, const std::string& path) {
    object(v, path);
    switch (choice(require(v, path, "type"), member(path, "type"), "object type", kObjectTypes)) {
      case 0: read_sphere(v, path); break;
      case 1: read_plane(v, path); break;
      case 2: read_polygon(v, path); break;
      case 3: read_quadric(v, path); break;
      case 4: read_mesh(v, path); break;
      default: read_instance(v, path); break;
    }
  }

  void read_sphere(const Json& v, const std::string& path) {
    check_keys(v, path, kSphereKeys);
    Sphere s;
    s.center = vector(v, path, "center", Vec3f(0.0f));
    s.radius = number(v, path, "radius", 1.0f, kPositive);
    s.material = material(v, path);
    add(path, [&] { scene_.add_sphere(s); });
  }

  void read_plane(const Json& v, const std::string& path) {
    check_keys(v, path, kPlaneKeys);
    Plane p;
    p.normal = Vec3f(direction(v, path, "normal", Vec3d(0.0, 1.0, 0.0)));
    p.d = -number(v, path, "offset", 0.0f, kAnyNumber);
    p.material = material(v, path);
    add(path, [&] { scene_.add_plane(p); });
  }

  void read_polygon(const Json& v, const std::string& path) {
    check_keys(v, path, kPolygonKeys);
    const std::string vp = member(path, "vertices");
    const Json& list = require(v, path, "vertices");
    if (!list.is_array() || list.size() < 3)
      fail(vp, cat("expected an array of at least 3 vertices, got ", show(list)));
    std::vector<Vec3f> vertices;
    for (size_t i = 0; i < list.size(); ++i) vertices.push_back(vector(list[i], element(vp, i)));
    // Scene::add_polygon's own test for a zero-area polygon, in float.
    if (!(length(polygon_plane<float>(vertices).n) > 0.0f))
      fail(vp, cat(show(list), " has zero area (the vertices are collinear)"));
    // Coplanarity, in double: every vertex within 1e-4 of the box diagonal from the plane.
    std::vector<Vec3d> dv(vertices.begin(), vertices.end());
    const PolygonPlane<double> plane = polygon_plane<double>(dv);
    const double n = length(plane.n);
    Box3d box;
    for (const Vec3d& p : dv) box.extend(p);
    const double tolerance = 1e-4 * length(box.extent());
    for (size_t i = 0; i < dv.size(); ++i) {
      const double distance = std::abs(dot(plane.n, dv[i]) + plane.d) / n;
      if (!(distance <= tolerance))
        fail(element(vp, i),
             cat(show(list[i]), " is ", distance, " off the polygon's plane (the vertices must be coplanar)"));
    }
    const uint32_t m = material(v, path);
    add(path, [&] { scene_.add_polygon(vertices, m); });
  }

  void read_quadric(const Json& v, const std::string& path) {
    const Json* shape = find(v, "shape");
    const Json* coefficients = find(v, "coefficients");
    if (shape != nullptr && coefficients != nullptr) fail(path, "expected \"shape\" or \"coefficients\", not both");
    if (shape == nullptr && coefficients == nullptr) fail(path, "missing key \"shape\" (or \"coefficients\")");
    QuadricShape q;
    if (coefficients != nullptr) {
      q.quadric = general_quadric(v, *coefficients, path);
    } else {
      q.quadric = named_quadric(v, *shape, path);
    }
    q.material = material(v, path);
    add(path, [&] { scene_.add_quadric(q); });
  }

  Quadricf general_quadric(const Json& v, const Json& coefficients, const std::string& path) const {
    check_keys(v, path, kGeneralQuadricKeys);
    const std::string cp = member(path, "coefficients");
    object(coefficients, cp);
    check_keys(coefficients, cp, kCoefficientKeys);
    Quadricf q;
    float* terms[] = {&q.A, &q.B, &q.C, &q.D, &q.E, &q.F, &q.G, &q.H, &q.I, &q.J};
    bool surface = false;
    for (size_t i = 0; i < 10; ++i) {
      *terms[i] = number(coefficients, cp, kCoefficientKeys[i], 0.0f, kAnyNumber);
      surface = surface || (i < 9 && *terms[i] != 0.0f);
    }
    if (!surface) fail(cp, cat(show(coefficients), " has no x, y or z term (one of A..I must be non-zero)"));
    q.center = vector(v, path, "center", Vec3f(0.0f));
    const std::string clip_path = member(path, "clip");
    const Json& clip = object(require(v, path, "clip"), clip_path);
    check_keys(clip, clip_path, kClipKeys);
    const Json& lo = require(clip, clip_path, "min");
    const Json& hi = require(clip, clip_path, "max");
    q.clip.lo = vector(lo, member(clip_path, "min"));
    q.clip.hi = vector(hi, member(clip_path, "max"));
    for (int k = 0; k < 3; ++k)
      if (!(q.clip.hi[k] >= q.clip.lo[k]))
        fail(element(member(clip_path, "max"), size_t(k)),
             cat(show(hi[size_t(k)]), " is out of range (must be >= min[", k, "] = ", show(lo[size_t(k)]), ")"));
    return q;
  }

  Quadricf named_quadric(const Json& v, const Json& shape, const std::string& path) const {
    const size_t kind = choice(shape, member(path, "shape"), "quadric shape", kShapes);
    static constexpr std::span<const std::string_view> kKeys[] = {kEllipsoidKeys,   kCylinderKeys,    kConeKeys,
                                                                  kHyperboloidKeys, kHyperboloidKeys, kParaboloidKeys};
    check_keys(v, path, kKeys[kind]);
    const Vec3f center = vector(v, path, "center", Vec3f(0.0f));
    int axis = 1;
    if (const Json* a = find(v, "axis")) axis = int(choice(*a, member(path, "axis"), "axis", kAxes));
    // Parameters are read in the documented order, so the first bad one is the one reported.
    auto length_of = [&](std::string_view key) { return number(v, path, key, 1.0f, kPositive); };
    if (kind == 0) return Quadricf::ellipsoid(center, vector(v, path, "radii", Vec3f(1.0f), kPositive));
    const float a = length_of(kind == 1 ? "radius_a" : "a");
    const float b = length_of(kind == 1 ? "radius_b" : "b");
    if (kind == 1) return Quadricf::cylinder(center, a, b, length_of("half_height"), axis);
    if (kind == 2) return Quadricf::cone(center, a, b, length_of("half_height"), axis);
    if (kind == 5) return Quadricf::paraboloid(center, a, b, length_of("height"), axis);
    const float c = length_of("c");
    if (kind == 3) return Quadricf::hyperboloid_one_sheet(center, a, b, c, length_of("half_height"), axis);
    const float half_height = number(v, path, "half_height", 2.0f * c, kPositive);
    if (!(half_height > c))
      fail(member(path, "half_height"), cat(show(*find(v, "half_height")), " is out of range (must be > c = ", c, ")"));
    return Quadricf::hyperboloid_two_sheets(center, a, b, c, half_height, axis);
  }

  MeshTransform transform(const Json& v, const std::string& path) const {
    MeshTransform t;
    object(v, path);
    check_keys(v, path, kTransformKeys);
    if (const Json* s = find(v, "scale")) {
      const std::string sp = member(path, "scale");
      if (s->is_number())
        t.scale = Vec3d(number(*s, sp, kPositive));
      else if (s->is_array() && s->size() == 3)
        t.scale = Vec3d(vector(*s, sp, kPositive));
      else
        fail(sp, cat("expected a number or 3 numbers, got ", show(*s)));
    }
    if (const Json* r = find(v, "rotate")) {
      const std::string rp = member(path, "rotate");
      object(*r, rp);
      check_keys(*r, rp, kRotateKeys);
      t.rotation =
          rotation_matrix(direction(*r, rp, "axis", Vec3d(0.0, 1.0, 0.0)), number(*r, rp, "degrees", 0.0f, kAnyNumber));
    }
    t.translation = Vec3d(vector(v, path, "translate", Vec3f(0.0f)));
    return t;
  }

  /// A mesh file as an object of `v` names it (its "file" and "material" keys): checked,
  /// not yet loaded.
  struct MeshFile {
    std::string file_path;  ///< JSON path of "file"
    std::string resolved;   ///< the file, relative to the scene's folder
    std::string ext;
    bool override_material = false;
    uint32_t material = 0;
  };
  MeshFile mesh_file(const Json& v, const std::string& path) const {
    MeshFile f;
    f.file_path = member(path, "file");
    const Json& file_value = require(v, path, "file");
    const std::string file = string(file_value, f.file_path);
    f.ext = lower_extension(file);
    if (f.ext != ".obj" && f.ext != ".ply")
      fail(f.file_path, cat(show(file_value), " is not a mesh file (expected .obj or .ply)"));
    f.override_material = find(v, "material") != nullptr;
    f.material = material(v, path);
    f.resolved = (dir_ / file).string();  // an absolute `file` as it is
    return f;
  }

  /// The meshes of `f`, their materials already in the scene (appended once, or the override).
  std::vector<TriangleMesh> load_meshes(const MeshFile& f) {
    Scene loaded;
    try {
      if (f.ext == ".obj")
        load_obj(f.resolved, loaded);
      else
        load_ply(f.resolved, loaded);
    } catch (const Error& e) {
      fail(f.file_path, e.what());
    }
    if (loaded.triangle_count() == 0) fail(f.file_path, cat(f.resolved, ": the file has no triangles"));
    // The file's materials 1.. follow the scene's; its material 0 is the scene's default too.
    const uint32_t base = uint32_t(scene_.materials().size()) - 1;
    if (!f.override_material)
      for (size_t i = 1; i < loaded.materials().size(); ++i)
        add(f.file_path, [&] { scene_.add_material(loaded.materials()[i]); });
    auto remap = [&](uint32_t id) { return f.override_material ? f.material : (id == 0 ? 0 : base + id); };
    std::vector<TriangleMesh> meshes;
    for (const MeshView& view : loaded.meshes()) meshes.push_back(to_triangle_mesh(view));
    for (TriangleMesh& mesh : meshes) {
      mesh.material = remap(mesh.material);
      if (f.override_material)
        mesh.face_materials.clear();
      else
        for (uint32_t& m : mesh.face_materials) m = remap(m);
    }
    return meshes;
  }

  /// Adds `meshes` to the world, mapped by `t` (positions, and normals by the inverse transpose).
  void bake(std::vector<TriangleMesh> meshes, const MeshTransform& t, const std::string& path) {
    for (TriangleMesh& mesh : meshes) {
      for (Vec3f& p : mesh.positions) p = t.point(p);
      for (Vec3f& n : mesh.normals) n = t.normal(n);
      add(path, [&] { scene_.add_mesh(std::move(mesh)); });
    }
  }

  MeshTransform transform_of(const Json& v, const std::string& path) const {
    const Json* transform_value = find(v, "transform");
    return transform_value != nullptr ? transform(*transform_value, member(path, "transform")) : MeshTransform{};
  }

  void read_mesh(const Json& v, const std::string& path) {
    check_keys(v, path, kMeshKeys);
    const MeshFile f = mesh_file(v, path);
    const MeshTransform t = transform_of(v, path);
    bake(load_meshes(f), t, path);
  }

  /// A mesh of "meshes" and the objects that place it.
  struct DeclaredMesh {
    std::string name, path;
    MeshFile file;
    std::vector<std::pair<MeshTransform, std::string>> placements;  ///< transform, object path
  };

  void read_declared_meshes(const Json& v, const std::string& path) {
    object(v, path);
    for (const auto& [name, value] : v.items()) {
      const std::string mp = member(path, name);
      object(value, mp);
      check_keys(value, mp, kDeclaredMeshKeys);
      declared_ids_.emplace(name, declared_.size());
      declared_.push_back({name, mp, mesh_file(value, mp), {}});
    }
  }

  void read_instance(const Json& v, const std::string& path) {
    check_keys(v, path, kInstanceKeys);
    const std::string mp = member(path, "mesh");
    const Json& name_value = require(v, path, "mesh");
    const std::string name = string(name_value, mp);
    const auto it = declared_ids_.find(name);
    if (it == declared_ids_.end()) {
      std::vector<std::string_view> names;
      for (const DeclaredMesh& d : declared_) names.push_back(d.name);
      fail(mp, cat("unknown mesh ", show(name_value), " (",
                   names.empty() ? std::string("no meshes are declared") : "meshes: " + join(names), ")"));
    }
    declared_[it->second].placements.emplace_back(transform_of(v, path), path);
  }

  /// Each declared mesh: baked where one object places it, stored once and instanced where
  /// several do (see "meshes" in docs/scene-formats.md).
  void place_declared_meshes() {
    for (DeclaredMesh& d : declared_) {
      if (d.placements.empty()) {
        warn(cat(file_, ": ", d.path, ": no object places this mesh; it is not loaded"));
        continue;
      }
      std::vector<TriangleMesh> meshes = load_meshes(d.file);
      if (d.placements.size() == 1) {
        bake(std::move(meshes), d.placements[0].first, d.placements[0].second);
        continue;
      }
      std::vector<uint32_t> ids;
      for (TriangleMesh& mesh : meshes) add(d.path, [&] { ids.push_back(scene_.add_instanced_mesh(std::move(mesh))); });
      for (const auto& [t, path] : d.placements) {
        const Affine3f a = t.affine();
        for (uint32_t id : ids) add(path, [&] { scene_.add_instance(id, a); });
      }
    }
  }

  std::string file_;
  std::filesystem::path dir_;  ///< the folder of file_, which mesh files are relative to
  Scene& scene_;
  std::vector<std::pair<std::string, uint32_t>> materials_;  ///< name, id; in file order
  std::unordered_map<std::string, uint32_t> material_ids_;   ///< name -> id, for look-ups
  std::vector<DeclaredMesh> declared_;                       ///< "meshes", in file order
  std::unordered_map<std::string, size_t> declared_ids_;     ///< name -> place in declared_
};

}  // namespace

void load_json_scene(const std::string& path, Scene& scene) {
  const std::string text = read_file(path);
  check_json_depth(path, text);  // messages print values recursively: the depth is bounded first
  const MemoryReserve reserve(json_unwind_reserve(text.size()));  // outlives root: see memory_reserve.h
  Json root;
  try {
    root = parse_ordered_json(text);
  } catch (const Json::parse_error& e) {
    const TextPosition at = position_of(text, e.byte);
    throw Error(cat(path, ": line ", at.line, ", column ", at.column, ": ", json_reason(e.what())));
  } catch (const Json::exception& e) {
    // out_of_range.406, a number too large for a double: nlohmann gives no position.
    throw Error(cat(path, ": ", json_reason(e.what())));
  }
  SceneReader(path, scene).read(root);
}

}  // namespace rp
