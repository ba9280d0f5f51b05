/// OBJ (+MTL) loading: tinyobjloader 2.0.0rc10 (Debian 12) parses the text; this file
/// triangulates, de-indexes, maps materials and validates.
///
/// Polygons are triangulated here, not by tinyobj: in rc10 ObjReaderConfig::triangulation_method
/// is documented as "Currently not used", Debian builds the library without mapbox earcut
/// (TINYOBJLOADER_USE_MAPBOX_EARCUT), and the built-in triangulator splits every quad along its
/// shorter diagonal (a triangle outside a non-convex quad) and clips larger polygons with an
/// orientation test that depends on where the origin is (a translated L-shape or star loses or
/// overlaps triangles). So tinyobj returns whole faces (triangulate = false) and each polygon is
/// ear-clipped in its own plane into exactly n - 2 triangles.

#include <sys/stat.h>
#include <tiny_obj_loader.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <istream>
#include <limits>
#include <map>
#include <span>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

#include "base/error.h"
#include "base/text.h"
#include "io/input_file.h"
#include "io/loaders/load.h"

namespace rp {
namespace {

// ---- strict numbers ----------------------------------------------------------------------
// tinyobjloader reads a number that does not parse as 0 ("v 1 abc 0"), stops at the first
// non-digit ("1x" is 1) and reads indices with atoi (4294967299 wraps to 3). Every line it
// takes numbers from is therefore checked here first, split into lines and fields exactly as
// tinyobj splits them, with the line number in the message.

bool is_blank(char c) { return c == ' ' || c == '\t'; }

/// The grammar tinyobj accepts, required to cover the whole field: an optional sign, digits
/// with an optional fraction (or a fraction alone), an optional exponent. A finite float is
/// returned; anything else throws naming the line.
float strict_number(const std::string& path, size_t line, std::string_view field) {
  size_t i = 0, digits = 0;
  if (i < field.size() && (field[i] == '+' || field[i] == '-')) ++i;
  for (; i < field.size() && std::isdigit(static_cast<unsigned char>(field[i])); ++i) ++digits;
  if (i < field.size() && field[i] == '.')
    for (++i; i < field.size() && std::isdigit(static_cast<unsigned char>(field[i])); ++i) ++digits;
  bool ok = digits > 0;
  if (ok && i < field.size() && (field[i] == 'e' || field[i] == 'E')) {
    ++i;
    if (i < field.size() && (field[i] == '+' || field[i] == '-')) ++i;
    size_t exponent_digits = 0;
    for (; i < field.size() && std::isdigit(static_cast<unsigned char>(field[i])); ++i) ++exponent_digits;
    ok = exponent_digits > 0;
  }
  const std::string shown = printable(field);
  if (!ok || i != field.size()) throw Error(cat(path, ": line ", line, ": '", shown, "' is not a number"));
  std::string_view digits_only = field[0] == '+' ? field.substr(1) : field;
  double value = 0.0;
  const auto r = std::from_chars(digits_only.data(), digits_only.data() + digits_only.size(), value);
  if (r.ec == std::errc::result_out_of_range) value = std::strtod(std::string(digits_only).c_str(), nullptr);
  if (!(std::abs(value) <= double(std::numeric_limits<float>::max())))
    throw Error(cat(path, ": line ", line, ": '", shown, "' is out of the float range"));
  return float(value);
}

/// An index field of a face, line or point ("i", "i/j", "i//k", "i/j/k"): each present index a
/// non-zero 32-bit integer; a negative (relative) one must reach back no further than the
/// first element read so far. `count` is what has been read of v, vt, vn; the largest
/// absolute index of each is kept with its line, for the check against the file's totals.
struct IndexCheck {
  size_t count[3] = {0, 0, 0};      ///< v, vt, vn read so far
  int64_t largest[3] = {0, 0, 0};   ///< largest absolute index of each
  size_t largest_line[3] = {0, 0, 0};
};
constexpr const char* kAttributeNames[3] = {"vertex", "texture coordinate", "normal"};
constexpr const char* kAttributePlurals[3] = {"vertices", "texture coordinates", "normals"};

void check_index_field(const std::string& path, size_t line, std::string_view field, IndexCheck& c) {
  int slot = 0;
  size_t start = 0;
  for (;;) {
    const size_t slash = field.find('/', start);
    const std::string_view part = field.substr(start, slash == std::string_view::npos ? slash : slash - start);
    if (!(part.empty() && slot == 1 && slash != std::string_view::npos)) {  // "i//k": no texture coordinate
      int64_t value = 0;
      const std::string_view digits = !part.empty() && part[0] == '+' ? part.substr(1) : part;
      const auto r = std::from_chars(digits.data(), digits.data() + digits.size(), value);
      if (digits.empty() || r.ptr != digits.data() + digits.size() || r.ec == std::errc::invalid_argument)
        throw Error(cat(path, ": line ", line, ": '", printable(field), "' is not an index (i, i/j, i//k or i/j/k)"));
      if (r.ec == std::errc::result_out_of_range || value == 0 || value > INT32_MAX || value < -int64_t(INT32_MAX))
        throw Error(cat(path, ": line ", line, ": ", kAttributeNames[slot], " index ", printable(part),
                        value == 0 && r.ec == std::errc() ? " is 0 (OBJ counts from 1)" : " is out of range"));
      if (value < 0 && size_t(-value) > c.count[slot])
        throw Error(cat(path, ": line ", line, ": relative ", kAttributeNames[slot], " index ", value, " reaches before the first (",
                        c.count[slot], " read so far)"));
      if (value > c.largest[slot]) {
        c.largest[slot] = value;
        c.largest_line[slot] = line;
      }
    }
    if (slash == std::string_view::npos) break;
    if (++slot > 2) throw Error(cat(path, ": line ", line, ": '", printable(field), "' has more than 3 indices"));
    start = slash + 1;
  }
}

/// Checks every number tinyobj would read from `text` (see above). Lines end at "\n", "\r"
/// or "\r\n" and at a NUL byte, as tinyobj reads them.
void check_obj_numbers(const std::string& path, std::string_view text) {
  IndexCheck c;
  std::vector<std::string_view> fields;
  size_t line = 0;
  for (size_t pos = 0; pos < text.size();) {
    size_t end = pos;
    while (end < text.size() && text[end] != '\n' && text[end] != '\r') ++end;
    std::string_view l = text.substr(pos, end - pos);
    pos = end < text.size() && text[end] == '\r' && end + 1 < text.size() && text[end + 1] == '\n' ? end + 2 : end + 1;
    ++line;
    if (const size_t nul = l.find('\0'); nul != std::string_view::npos) l = l.substr(0, nul);
    while (!l.empty() && is_blank(l.front())) l.remove_prefix(1);
    if (l.size() < 2) continue;
    const bool v = l[0] == 'v' && is_blank(l[1]);
    const bool vn = l.size() > 2 && l[0] == 'v' && l[1] == 'n' && is_blank(l[2]);
    const bool vt = l.size() > 2 && l[0] == 'v' && l[1] == 't' && is_blank(l[2]);
    const bool vw = l.size() > 2 && l[0] == 'v' && l[1] == 'w' && is_blank(l[2]);
    const bool indices = (l[0] == 'f' || l[0] == 'l' || l[0] == 'p') && is_blank(l[1]);
    if (!v && !vn && !vt && !vw && !indices) continue;
    split_fields(l.substr(v || indices ? 2 : 3), is_blank, fields);
    if (indices) {
      for (std::string_view f : fields) check_index_field(path, line, f, c);
      continue;
    }
    if (vw) {  // tinyobj's skin weights, "vw vertex joint weight ...": unused here, but read
      // by tinyobj, which converts each joint to an int (undefined past the int range).
      if (fields.empty() || fields.size() % 2 == 0)
        throw Error(cat(path, ": line ", line, ": a skin weight ('vw') takes a vertex and joint-weight pairs, got ",
                        fields.size(), " numbers"));
      for (size_t k = 0; k < fields.size(); ++k) {
        const float x = strict_number(path, line, fields[k]);
        if ((k == 0 || k % 2 == 1) && !(std::abs(x) < 2147483648.0f))
          throw Error(cat(path, ": line ", line, ": skin weight ", k == 0 ? "vertex " : "joint ", printable(fields[k]),
                          " is out of range"));
      }
      continue;
    }
    const size_t lo = v ? 3 : vn ? 3 : 1, hi = v ? 7 : vn ? 3 : 3;
    const char* what = v ? "a vertex ('v')" : vn ? "a normal ('vn')" : "a texture coordinate ('vt')";
    if (fields.size() < lo || fields.size() > hi)
      throw Error(cat(path, ": line ", line, ": ", what, " takes ", lo == hi ? cat(lo) : cat(lo, " to ", hi),
                      " numbers, got ", fields.size()));
    for (size_t k = 0; k < fields.size(); ++k) {
      const float x = strict_number(path, line, fields[k]);
      if (v && k < 3 && !(std::abs(x) <= kMaxCoordinate))
        throw Error(cat(path, ": line ", line, ": vertex coordinate ", printable(fields[k]),
                        " is outside the supported coordinate range |x| <= 1073741824 (2^30)"));
    }
    ++c.count[v ? 0 : vt ? 1 : 2];
  }
  for (int k = 0; k < 3; ++k)
    if (size_t(c.largest[k]) > c.count[k])
      throw Error(cat(path, ": line ", c.largest_line[k], ": ", kAttributeNames[k], " index ", c.largest[k],
                      " is past the file's ", c.count[k], " ", kAttributePlurals[k]));
}

std::string first_line(const std::string& text) {
  std::string line = text.substr(0, text.find('\n'));
  while (!line.empty() && std::isspace(static_cast<unsigned char>(line.back()))) line.pop_back();
  return line;
}

/// tinyobj's warning text on one line: its first meaningful line, plus how many more there are
/// (a missing MTL yields one line for the file and one per `usemtl`). Lines without a letter or
/// digit (rc10 writes "Degenerated face found\n.") are dropped.
std::string one_line_warning(const std::string& text) {
  std::string first;
  size_t more = 0;
  size_t begin = 0;
  while (begin < text.size()) {
    size_t end = text.find('\n', begin);
    if (end == std::string::npos) end = text.size();
    std::string line = text.substr(begin, end - begin);
    begin = end + 1;
    while (!line.empty() && std::isspace(static_cast<unsigned char>(line.back()))) line.pop_back();
    if (std::none_of(line.begin(), line.end(), [](unsigned char c) { return std::isalnum(c) != 0; })) continue;
    if (first.empty())
      first = line;
    else
      ++more;
  }
  if (more > 0) first += cat(" (and ", more, more == 1 ? " more warning)" : " more warnings)");
  return first;
}

/// MTL → Material: Kd, Ks, Ns, Ke, Ni and d map one to one. mirror is the mean of Ks for
/// illum 3 (ray-traced reflection) and 5 (Fresnel reflection), clamped to [0, 1], else 0;
/// illum 7 (refraction) is left to d and Ni. Ni below 1 (exporters write 0 for "not set") reads
/// as 1. tinyobj fills what a material leaves out: Kd = Ks = Ke = 0, Ns = 1, Ni = 1, d = 1.
Material to_material(const tinyobj::material_t& m) {
  Material out;
  out.name = m.name;
  out.diffuse = {m.diffuse[0], m.diffuse[1], m.diffuse[2]};
  out.specular = {m.specular[0], m.specular[1], m.specular[2]};
  out.shininess = m.shininess;
  out.emission = {m.emission[0], m.emission[1], m.emission[2]};
  out.ior = m.ior >= 0.0f && m.ior < 1.0f ? 1.0f : m.ior;
  out.opacity = m.dissolve;
  if (m.illum == 3 || m.illum == 5)
    out.mirror = std::clamp((m.specular[0] + m.specular[1] + m.specular[2]) / 3.0f, 0.0f, 1.0f);
  return out;
}

double cross2(double ax, double ay, double bx, double by) { return ax * by - ay * bx; }

/// Triangulates the simple polygon `p` (n >= 3 corners, any orientation, roughly planar) into
/// n - 2 triangles of local corner indices appended to `out`, keeping the polygon's winding.
/// The polygon is projected along the dominant axis of its Newell normal; quads take the
/// shorter valid diagonal; larger polygons are ear-clipped (Eberly, "Triangulation by Ear
/// Clipping", Geometric Tools 2002, section 2: clip convex corners whose triangle holds no other
/// corner). A polygon with no ear (self-intersecting or collinear) has its current corner
/// clipped anyway, so the count is always n - 2.
void triangulate_polygon(std::span<const Vec3d> p, std::vector<double>& scratch, std::vector<uint32_t>& links,
                         std::vector<uint32_t>& out) {
  const uint32_t n = uint32_t(p.size());
  if (n == 3) {
    out.insert(out.end(), {0u, 1u, 2u});
    return;
  }
  Vec3d normal{0.0};
  for (uint32_t i = 0; i < n; ++i) normal += cross(p[i], p[(i + 1) % n]);
  const int axis = max_abs_axis(normal);
  int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
  if (normal[axis] < 0.0) std::swap(a1, a2);  // the projection is counter-clockwise
  scratch.resize(2 * n);
  for (uint32_t i = 0; i < n; ++i) {
    scratch[2 * i] = p[i][a1];
    scratch[2 * i + 1] = p[i][a2];
  }
  const double* q = scratch.data();
  // Twice the signed area of corners (a, b, c) in the projection.
  auto area2 = [q](uint32_t a, uint32_t b, uint32_t c) {
    return cross2(q[2 * b] - q[2 * a], q[2 * b + 1] - q[2 * a + 1], q[2 * c] - q[2 * a], q[2 * c + 1] - q[2 * a + 1]);
  };

  if (n == 4) {
    const bool d02 = area2(0, 1, 2) > 0.0 && area2(0, 2, 3) > 0.0;
    const bool d13 = area2(0, 1, 3) > 0.0 && area2(1, 2, 3) > 0.0;
    const double len02 = dot(p[2] - p[0], p[2] - p[0]), len13 = dot(p[3] - p[1], p[3] - p[1]);
    if (d13 && (!d02 || len13 < len02))
      out.insert(out.end(), {0u, 1u, 3u, 1u, 2u, 3u});
    else
      out.insert(out.end(), {0u, 1u, 2u, 0u, 2u, 3u});
    return;
  }

  // Doubly linked ring of the corners not yet clipped: prev in links[0, n), next in links[n, 2n).
  links.resize(2 * n);
  uint32_t* prev = links.data();
  uint32_t* next = links.data() + n;
  for (uint32_t i = 0; i < n; ++i) {
    prev[i] = (i + n - 1) % n;
    next[i] = (i + 1) % n;
  }
  auto is_ear = [&](uint32_t a, uint32_t i, uint32_t b) {
    if (area2(a, i, b) <= 0.0) return false;  // reflex or collinear corner
    for (uint32_t j = next[b]; j != a; j = next[j]) {
      if (p[j] == p[a] || p[j] == p[i] || p[j] == p[b]) continue;  // a repeated corner
      if (area2(a, i, j) >= 0.0 && area2(i, b, j) >= 0.0 && area2(b, a, j) >= 0.0) return false;
    }
    return true;
  };
  uint32_t remaining = n, i = 0, tries = n;
  while (remaining > 3) {
    const uint32_t a = prev[i], b = next[i];
    if (is_ear(a, i, b) || tries == 0) {
      out.insert(out.end(), {a, i, b});
      next[a] = b;
      prev[b] = a;
      --remaining;
      tries = remaining;
      i = a;
    } else {
      --tries;
      i = b;
    }
  }
  out.insert(out.end(), {prev[i], i, next[i]});
}

/// A corner's (position, normal, texcoord) indices; -1 for an attribute the mesh doesn't keep.
struct CornerKey {
  int v, n, t;
  friend bool operator==(const CornerKey&, const CornerKey&) = default;
};
struct CornerKeyHash {
  size_t operator()(const CornerKey& k) const {
    uint64_t h = uint64_t(uint32_t(k.v)) * 0x9E3779B185EBCA87ull ^ uint64_t(uint32_t(k.n)) * 0xC2B2AE3D27D4EB4Full ^
                 uint64_t(uint32_t(k.t)) * 0x165667B19E3779F9ull;
    return size_t(h ^ (h >> 31));
  }
};

/// Reads the `mtllib` files of an OBJ from the OBJ's folder as tinyobj's MaterialFileReader
/// does (same warning for a missing file), but by the rule of io/input_file.h: tinyobj's
/// reader opens whatever the name reaches, so "mtllib ../../dev/zero" read one endless line
/// until memory ran out, and a FIFO or a terminal blocked the load. Such a file is skipped
/// with a warning.
class RegularMtlReader final : public tinyobj::MaterialReader {
 public:
  explicit RegularMtlReader(std::string dir) : dir_(std::move(dir)) {}

  bool operator()(const std::string& name, std::vector<tinyobj::material_t>* materials,
                  std::map<std::string, int>* ids, std::string* warn, std::string* err) override {
    const std::string file = dir_ + name;
    struct stat st {};
    if (::stat(file.c_str(), &st) != 0) {
      if (warn) *warn += cat("Material file [ ", name, " ] not found in a path : ", dir_, "\n");
      return false;
    }
    std::string text;
    try {
      text = read_file(file);
    } catch (const Error& e) {
      if (warn) *warn += cat("Material file [ ", name, " ] not read: ", e.what(), "\n");
      return false;
    }
    MemoryStreambuf buffer(text.data(), text.size());
    std::istream in(&buffer);
    tinyobj::LoadMtl(ids, materials, &in, warn, err);
    return true;
  }

 private:
  std::string dir_;  ///< the OBJ's folder with a trailing '/', or empty for the working folder
};

}  // namespace

void load_obj(const std::string& path, Scene& scene) {
  const std::string text = read_file(path);
  check_obj_numbers(path, text);
  MemoryStreambuf buffer(text.data(), text.size());
  std::istream in(&buffer);
  RegularMtlReader mtl_reader(std::filesystem::path(path).remove_filename().string());
  tinyobj::attrib_t attrib;
  std::vector<tinyobj::shape_t> shapes;
  std::vector<tinyobj::material_t> materials;
  std::string warning, error;
  if (!tinyobj::LoadObj(&attrib, &shapes, &materials, &warning, &error, &in, &mtl_reader,
                        /*triangulate=*/false, /*default_vcols_fallback=*/false))  // see the top of this file
    throw Error(cat(path, ": ", first_line(error)));

  const std::vector<float>& vertices = attrib.vertices;
  const size_t nv = vertices.size() / 3, nn = attrib.normals.size() / 3, nt = attrib.texcoords.size() / 2;
  for (size_t i = 0; i < vertices.size(); ++i)
    RP_CHECK(std::isfinite(vertices[i]), path, ": vertex ", i / 3 + 1, " has a non-finite coordinate");

  const uint32_t first_material = uint32_t(scene.materials().size());
  try {
    for (const tinyobj::material_t& m : materials) scene.add_material(to_material(m));
  } catch (const Error& e) {
    throw Error(cat(path, ": ", e.what()));
  }
  auto material_of = [&](int id) { return id < 0 || size_t(id) >= materials.size() ? 0u : first_material + uint32_t(id); };

  // Scratch reused across faces and meshes: no allocation per vertex.
  std::unordered_map<CornerKey, uint32_t, CornerKeyHash> vertex_of;
  std::vector<uint32_t> face_vertices, local_triangles, links;
  std::vector<Vec3d> polygon;
  std::vector<double> projected;
  size_t face_number = 0;  // 1-based over the file's faces of 3+ corners, in file order

  for (const tinyobj::shape_t& shape : shapes) {
    const tinyobj::mesh_t& m = shape.mesh;
    if (m.num_face_vertices.empty()) continue;  // lines or points only
    size_t corners = 0, triangles = 0;
    for (unsigned char count : m.num_face_vertices) {
      corners += count;
      triangles += count >= 3 ? count - 2u : 0u;
    }
    const std::string name = shape.name.empty() ? std::filesystem::path(path).stem().string() : shape.name;
    RP_CHECK(corners == m.indices.size(), path, ": mesh '", name,
             "' has a face of more than 255 corners, which tinyobjloader 2.0.0rc10 cannot represent");

    // Pass 1: index ranges, which attributes every corner has, how many materials.
    bool has_normals = nn > 0, has_uvs = nt > 0, several_materials = false;
    size_t corner = 0;
    for (size_t f = 0; f < m.num_face_vertices.size(); ++f) {
      const size_t face = face_number + f + 1;
      for (unsigned k = 0; k < m.num_face_vertices[f]; ++k, ++corner) {
        const tinyobj::index_t& idx = m.indices[corner];
        RP_CHECK(idx.vertex_index >= 0 && size_t(idx.vertex_index) < nv, path, ": face ", face, " uses vertex ",
                 int64_t(idx.vertex_index) + 1, " of ", nv);
        RP_CHECK(idx.normal_index >= -1 && (idx.normal_index < 0 || size_t(idx.normal_index) < nn), path, ": face ",
                 face, " uses normal ", int64_t(idx.normal_index) + 1, " of ", nn);
        RP_CHECK(idx.texcoord_index >= -1 && (idx.texcoord_index < 0 || size_t(idx.texcoord_index) < nt), path,
                 ": face ", face, " uses texture coordinate ", int64_t(idx.texcoord_index) + 1, " of ", nt);
        has_normals = has_normals && idx.normal_index >= 0;
        has_uvs = has_uvs && idx.texcoord_index >= 0;
      }
      several_materials = several_materials || material_of(m.material_ids[f]) != material_of(m.material_ids[0]);
    }

    // Pass 2: one vertex per distinct kept (position, normal, texcoord) triple.
    TriangleMesh mesh;
    mesh.name = name;
    mesh.material = material_of(m.material_ids[0]);
    vertex_of.clear();
    vertex_of.reserve(corners);
    mesh.positions.reserve(std::min(corners, nv));
    if (has_normals) mesh.normals.reserve(std::min(corners, nv));
    if (has_uvs) mesh.uvs.reserve(std::min(corners, nv));
    mesh.indices.reserve(3 * triangles);
    if (several_materials) mesh.face_materials.reserve(triangles);
    corner = 0;
    for (size_t f = 0; f < m.num_face_vertices.size(); ++f) {
      const unsigned count = m.num_face_vertices[f];
      face_vertices.clear();
      for (unsigned k = 0; k < count; ++k, ++corner) {
        const tinyobj::index_t& idx = m.indices[corner];
        const CornerKey key{idx.vertex_index, has_normals ? idx.normal_index : -1, has_uvs ? idx.texcoord_index : -1};
        auto [it, inserted] = vertex_of.try_emplace(key, uint32_t(mesh.positions.size()));
        if (inserted) {
          const float* v = &vertices[3 * size_t(key.v)];
          mesh.positions.push_back({v[0], v[1], v[2]});
          if (has_normals) {
            const float* n = &attrib.normals[3 * size_t(key.n)];
            mesh.normals.push_back({n[0], n[1], n[2]});
          }
          if (has_uvs) {
            const float* t = &attrib.texcoords[2 * size_t(key.t)];
            mesh.uvs.push_back({t[0], t[1]});
          }
        }
        face_vertices.push_back(it->second);
      }
      if (count == 3) {
        mesh.indices.insert(mesh.indices.end(), face_vertices.begin(), face_vertices.end());
      } else {
        polygon.clear();
        for (uint32_t v : face_vertices) polygon.push_back(Vec3d(mesh.positions[v]));
        local_triangles.clear();
        triangulate_polygon(polygon, projected, links, local_triangles);
        for (uint32_t k : local_triangles) mesh.indices.push_back(face_vertices[k]);
      }
      if (several_materials) mesh.face_materials.resize(mesh.indices.size() / 3, material_of(m.material_ids[f]));
    }
    face_number += m.num_face_vertices.size();
    try {
      scene.add_mesh(std::move(mesh));
    } catch (const Error& e) {
      throw Error(cat(path, ": ", e.what()));
    }
  }

  if (!warning.empty())
    warn(cat(path, ": ", one_line_warning(warning)));
}

}  // namespace rp
