/// PLY loading (ascii, binary little and big endian), written by hand: Debian 12 packages no
/// small, well-kept PLY-only library, and assimp is large and imports PLY into its own scene
/// graph with a copy of every array, while 871k-triangle binary scans want a path that copies
/// straight from the file bytes into the mesh arrays.
///
/// The file is mapped once (rp::MappedFile: regular files only); the header is parsed line by line; before anything is
/// allocated, the bytes every element needs at the least are checked against the bytes after
/// the header (so "element vertex 4000000000" in a small file is refused, not allocated). The
/// common binary layout (native-endian float x y z among scalar properties; faces as one list
/// with a one-byte count and 32-bit indices) is copied with memcpy; any other layout goes
/// through a general reader. Numbers in messages count from 0, as PLY indices do.

#include <algorithm>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "base/error.h"
#include "base/text.h"
#include "io/input_file.h"
#include "io/loaders/load.h"

namespace rp {
namespace {

static_assert(sizeof(Vec3f) == 12, "positions are copied from the file as packed float x y z");

enum class Type : uint8_t { i8, u8, i16, u16, i32, u32, f32, f64 };
constexpr size_t kTypeSize[] = {1, 1, 2, 2, 4, 4, 4, 8};
size_t size_of(Type t) { return kTypeSize[size_t(t)]; }
bool is_integer(Type t) { return t != Type::f32 && t != Type::f64; }

std::optional<Type> parse_type(std::string_view s) {
  struct Name {
    std::string_view name;
    Type type;
  };
  static constexpr Name kNames[] = {
      {"char", Type::i8},    {"uchar", Type::u8},    {"short", Type::i16},  {"ushort", Type::u16},
      {"int", Type::i32},    {"uint", Type::u32},    {"float", Type::f32},  {"double", Type::f64},
      {"int8", Type::i8},    {"uint8", Type::u8},    {"int16", Type::i16},  {"uint16", Type::u16},
      {"int32", Type::i32},  {"uint32", Type::u32},  {"float32", Type::f32}, {"float64", Type::f64}};
  for (const Name& n : kNames)
    if (n.name == s) return n.type;
  return std::nullopt;
}

struct Property {
  std::string name;
  Type type = Type::f32;  ///< the item type for a list
  bool list = false;
  Type count_type = Type::u8;
  size_t line = 0;
};

struct Element {
  std::string name;
  uint64_t count = 0;
  std::vector<Property> props;
  size_t line = 0;
};

enum class Format { ascii, binary_little_endian, binary_big_endian };

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f'; }

template <typename T>
T load(const char* p, bool swap) {
  T v;
  if (!swap) {
    std::memcpy(&v, p, sizeof v);
  } else {
    char b[sizeof(T)];
    for (size_t i = 0; i < sizeof(T); ++i) b[i] = p[sizeof(T) - 1 - i];
    std::memcpy(&v, b, sizeof v);
  }
  return v;
}

/// The value of type `t` at p, converted to R. Float types never reach R = int64_t: counts
/// and indices are checked to be integers when the header is read.
template <typename R>
R load_as(const char* p, Type t, bool swap) {
  switch (t) {
    case Type::i8: return R(load<int8_t>(p, swap));
    case Type::u8: return R(load<uint8_t>(p, swap));
    case Type::i16: return R(load<int16_t>(p, swap));
    case Type::u16: return R(load<uint16_t>(p, swap));
    case Type::i32: return R(load<int32_t>(p, swap));
    case Type::u32: return R(load<uint32_t>(p, swap));
    case Type::f32:
      if constexpr (std::is_floating_point_v<R>) return R(load<float>(p, swap));
      break;
    case Type::f64:
      if constexpr (std::is_floating_point_v<R>) return R(load<double>(p, swap));
      break;
  }
  return R(0);
}

double load_number(const char* p, Type t, bool swap) { return load_as<double>(p, t, swap); }

int64_t load_integer(const char* p, Type t, bool swap) { return load_as<int64_t>(p, t, swap); }

/// What a vertex property feeds: a position or normal component, or nothing.
enum Role : int8_t { kNone = -1, kX, kY, kZ, kNx, kNy, kNz };

class PlyReader {
 public:
  PlyReader(const std::string& path, const char* data, size_t size) : path_(path), data_(data), size_(size) {}

  TriangleMesh read() {
    parse_header();
    check_sizes();
    mesh_.positions.resize(size_t(vertex_->count));
    if (has_normals_) mesh_.normals.resize(size_t(vertex_->count));
    if (face_) mesh_.indices.reserve(3 * size_t(face_->count));
    size_t offset = data_begin_, line = header_lines_ + 1;
    for (const Element& e : elements_) {
      if (format_ == Format::ascii)
        read_ascii(e, offset, line);
      else
        read_binary(e, offset);
    }
    for (size_t i = 0; i < mesh_.positions.size(); ++i) {
      const Vec3f& p = mesh_.positions[i];
      RP_CHECK(is_finite(p), path_, ": vertex ", i, " has a non-finite coordinate");
      RP_CHECK(in_coordinate_range(p), path_, ": vertex ", i, " (", p.x, ", ", p.y, ", ", p.z,
               ") is outside the supported coordinate range |x| <= 1073741824 (2^30)");
    }
    return std::move(mesh_);
  }

 private:
  [[noreturn]] void fail_line(size_t line, const std::string& what) const {
    throw Error(cat(path_, ": line ", line, ": ", what));
  }

  void parse_header() {
    size_t pos = 0, line = 0;
    std::vector<std::string_view> tokens;
    auto next_line = [&](std::string_view& out) {
      if (pos >= size_) return false;
      const char* nl = static_cast<const char*>(std::memchr(data_ + pos, '\n', size_ - pos));
      const size_t end = nl ? size_t(nl - data_) : size_;
      out = std::string_view(data_ + pos, end - pos);
      if (!out.empty() && out.back() == '\r') out.remove_suffix(1);
      pos = nl ? end + 1 : size_;
      ++line;
      return true;
    };
    std::string_view text;
    if (!next_line(text) || text != "ply") fail_line(1, "not a PLY file (the first line is not 'ply')");
    bool have_format = false;
    for (;;) {
      if (!next_line(text)) fail_line(line, "end of file before 'end_header'");
      split_fields(text, is_space, tokens);
      if (tokens.empty() || tokens[0] == "comment" || tokens[0] == "obj_info") continue;
      const std::string_view key = tokens[0];
      if (key == "end_header") break;
      if (key == "format") {
        if (tokens.size() != 3) fail_line(line, "expected 'format TYPE 1.0'");
        if (tokens[1] == "ascii")
          format_ = Format::ascii;
        else if (tokens[1] == "binary_little_endian")
          format_ = Format::binary_little_endian;
        else if (tokens[1] == "binary_big_endian")
          format_ = Format::binary_big_endian;
        else
          fail_line(line, cat("unknown format '", tokens[1], "' (ascii, binary_little_endian, binary_big_endian)"));
        if (tokens[2] != "1.0") fail_line(line, cat("unsupported PLY version '", tokens[2], "' (1.0)"));
        have_format = true;
      } else if (key == "element") {
        if (tokens.size() != 3) fail_line(line, "expected 'element NAME COUNT'");
        Element e;
        e.name = std::string(tokens[1]);
        e.line = line;
        const std::string_view n = tokens[2];
        auto [end, ec] = std::from_chars(n.data(), n.data() + n.size(), e.count);
        if (ec != std::errc() || end != n.data() + n.size()) fail_line(line, cat("'", n, "' is not an element count"));
        elements_.push_back(std::move(e));
      } else if (key == "property") {
        if (elements_.empty()) fail_line(line, "'property' before any 'element'");
        Property p;
        p.line = line;
        auto type_of = [&](std::string_view s) {
          const std::optional<Type> t = parse_type(s);
          if (!t) fail_line(line, cat("unknown property type '", s, "'"));
          return *t;
        };
        if (tokens.size() >= 2 && tokens[1] == "list") {
          if (tokens.size() != 5) fail_line(line, "expected 'property list COUNT_TYPE ITEM_TYPE NAME'");
          p.list = true;
          p.count_type = type_of(tokens[2]);
          if (!is_integer(p.count_type)) fail_line(line, cat("list count type '", tokens[2], "' is not an integer type"));
          p.type = type_of(tokens[3]);
          p.name = std::string(tokens[4]);
        } else {
          if (tokens.size() != 3) fail_line(line, "expected 'property TYPE NAME'");
          p.type = type_of(tokens[1]);
          p.name = std::string(tokens[2]);
        }
        elements_.back().props.push_back(std::move(p));
      } else {
        fail_line(line, cat("unexpected '", key, "' in the header"));
      }
    }
    if (!have_format) fail_line(line, "no 'format' line before 'end_header'");
    header_lines_ = line;
    data_begin_ = pos;

    for (Element& e : elements_) {
      if (e.name == "vertex" && !vertex_) vertex_ = &e;
      if (e.name == "face" && !face_) face_ = &e;
    }
    if (!vertex_) throw Error(cat(path_, ": the header declares no 'vertex' element"));
    vertex_roles_.assign(vertex_->props.size(), kNone);
    static constexpr const char* kRoleNames[] = {"x", "y", "z", "nx", "ny", "nz"};
    int found[6] = {-1, -1, -1, -1, -1, -1};
    for (size_t i = 0; i < vertex_->props.size(); ++i)
      for (int r = 0; r < 6; ++r)
        if (vertex_->props[i].name == kRoleNames[r] && found[r] < 0) found[r] = int(i);
    for (int r = 0; r < 3; ++r) {
      if (found[r] < 0) fail_line(vertex_->line, cat("element 'vertex' has no property '", kRoleNames[r], "'"));
      const Property& p = vertex_->props[size_t(found[r])];
      if (p.list) fail_line(p.line, cat("property '", p.name, "' of element 'vertex' is a list"));
    }
    has_normals_ = true;
    for (int r = 3; r < 6; ++r)
      has_normals_ = has_normals_ && found[r] >= 0 && !vertex_->props[size_t(found[r])].list;
    for (int r = 0; r < (has_normals_ ? 6 : 3); ++r) vertex_roles_[size_t(found[r])] = Role(r);

    if (face_) {
      for (size_t i = 0; i < face_->props.size() && face_list_ < 0; ++i) {
        const Property& p = face_->props[i];
        if (p.list && (p.name == "vertex_indices" || p.name == "vertex_index")) face_list_ = int(i);
      }
      if (face_list_ < 0) fail_line(face_->line, "element 'face' has no list property 'vertex_indices'");
      const Property& p = face_->props[size_t(face_list_)];
      if (!is_integer(p.type)) fail_line(p.line, cat("property '", p.name, "' has items of a non-integer type"));
    }
  }

  /// Refuses element counts that cannot fit in the bytes after the header, before allocating.
  /// Binary: each item takes at least its scalars and list counts (a face's index list at least 3
  /// items). Ascii: each of those numbers takes at least 2 bytes (a digit and a blank), bar the
  /// last one in the file.
  void check_sizes() const {
    const uint64_t available = size_ - data_begin_;
    const uint64_t allowed = format_ == Format::ascii ? available + 1 : available;
    uint64_t needed = 0;
    for (const Element& e : elements_) {
      uint64_t per_item = 0;
      for (size_t i = 0; i < e.props.size(); ++i) {
        const Property& p = e.props[i];
        const bool face_list = &e == face_ && int(i) == face_list_;
        if (format_ == Format::ascii)
          per_item += p.list ? (face_list ? 8 : 2) : 2;
        else
          per_item += p.list ? size_of(p.count_type) + (face_list ? 3 * size_of(p.type) : 0) : size_of(p.type);
      }
      uint64_t bytes = 0;
      if (__builtin_mul_overflow(e.count, per_item, &bytes) || __builtin_add_overflow(needed, bytes, &needed) ||
          needed > allowed)
        throw Error(cat(path_, ": element '", e.name, "' declares ", e.count, " items but the file has only ",
                        available, " bytes after the header"));
    }
    RP_CHECK(vertex_->count <= UINT32_MAX, path_, ": line ", vertex_->line, ": ", vertex_->count,
             " vertices, more than 32-bit indices can address");
  }

  [[noreturn]] void fail_truncated(const Element& e, uint64_t item) const {
    throw Error(cat(path_, ": truncated: ", e.name, " ", item, " ends past the end of the file at byte offset ", size_));
  }

  [[noreturn]] void fail_index(uint64_t face, int64_t vertex) const {
    throw Error(cat(path_, ": face ", face, " uses vertex ", vertex, " of ", vertex_->count));
  }

  [[noreturn]] void fail_count(uint64_t face, int64_t count) const {
    throw Error(cat(path_, ": face ", face, " has ", count, " vertices (a face needs at least 3)"));
  }

  /// Appends the fan (v0, vk, vk+1) of a polygon's indices, each checked against the vertex count.
  template <typename Get>
  void add_face(uint64_t face, int64_t count, Get&& index_at) {
    if (count < 3) fail_count(face, count);
    const int64_t nv = int64_t(vertex_->count);
    auto checked = [&](int64_t k) {
      const int64_t v = index_at(k);
      if (v < 0 || v >= nv) fail_index(face, v);
      return uint32_t(v);
    };
    const uint32_t v0 = checked(0);
    uint32_t prev = checked(1);
    for (int64_t k = 2; k < count; ++k) {
      const uint32_t v = checked(k);
      mesh_.indices.insert(mesh_.indices.end(), {v0, prev, v});
      prev = v;
    }
  }

  void read_binary(const Element& e, size_t& offset) {
    const bool swap = (format_ == Format::binary_little_endian) != (std::endian::native == std::endian::little);
    const char* const end = data_ + size_;
    const char* p = data_ + offset;
    const bool all_scalar = std::none_of(e.props.begin(), e.props.end(), [](const Property& q) { return q.list; });
    size_t stride = 0;
    for (const Property& q : e.props) stride += q.list ? 0 : size_of(q.type);

    if (all_scalar) {
      // Fixed-size items: one bounds check for the whole element.
      const uint64_t fits = stride == 0 ? e.count : uint64_t(end - p) / stride;
      if (fits < e.count) fail_truncated(e, fits);
    }
    if (&e == vertex_ && all_scalar && !swap) {
      read_vertices_fast(p, stride);
    } else if (&e == face_ && !swap && e.props.size() == 1 && size_of(e.props[0].count_type) == 1 &&
               size_of(e.props[0].type) == 4) {
      p = read_faces_fast(e, p);
    } else if (&e == vertex_ || &e == face_) {
      for (uint64_t item = 0; item < e.count; ++item) {
        for (size_t i = 0; i < e.props.size(); ++i) {
          const Property& q = e.props[i];
          if (!q.list) {
            if (!all_scalar && size_t(end - p) < size_of(q.type)) fail_truncated(e, item);
            if (&e == vertex_ && vertex_roles_[i] != kNone)
              store_vertex(item, vertex_roles_[i], float(load_number(p, q.type, swap)));
            p += size_of(q.type);
            continue;
          }
          if (size_t(end - p) < size_of(q.count_type)) fail_truncated(e, item);
          const int64_t count = load_integer(p, q.count_type, swap);
          p += size_of(q.count_type);
          const bool indices = &e == face_ && int(i) == face_list_;
          if (indices && count < 3) fail_count(item, count);
          if (count < 0) throw Error(cat(path_, ": ", e.name, " ", item, " has a list of ", count, " items"));
          if (uint64_t(end - p) / size_of(q.type) < uint64_t(count)) fail_truncated(e, item);
          if (indices) {
            const size_t item_size = size_of(q.type);
            add_face(item, count, [&](int64_t k) { return load_integer(p + size_t(k) * item_size, q.type, swap); });
          }
          p += size_t(count) * size_of(q.type);
        }
      }
    } else if (all_scalar) {
      p += e.count * stride;
    } else {
      for (uint64_t item = 0; item < e.count; ++item)
        for (const Property& q : e.props) {
          if (!q.list) {
            if (size_t(end - p) < size_of(q.type)) fail_truncated(e, item);
            p += size_of(q.type);
            continue;
          }
          if (size_t(end - p) < size_of(q.count_type)) fail_truncated(e, item);
          const int64_t count = load_integer(p, q.count_type, swap);
          p += size_of(q.count_type);
          if (count < 0) throw Error(cat(path_, ": ", e.name, " ", item, " has a list of ", count, " items"));
          if (uint64_t(end - p) / size_of(q.type) < uint64_t(count)) fail_truncated(e, item);
          p += size_t(count) * size_of(q.type);
        }
    }
    offset = size_t(p - data_);
  }

  void store_vertex(uint64_t item, Role role, float value) {
    if (role <= kZ)
      mesh_.positions[item][role] = value;
    else
      mesh_.normals[item][role - kNx] = value;
  }

  /// Native-endian scalar vertices (bounds already checked): float components are copied,
  /// others converted.
  void read_vertices_fast(const char*& p, size_t stride) {
    const Element& e = *vertex_;
    if (e.count == 0) return;
    std::vector<size_t> offsets(e.props.size());
    size_t at = 0;
    for (size_t i = 0; i < e.props.size(); ++i) {
      offsets[i] = at;
      at += size_of(e.props[i].type);
    }
    auto role_index = [&](Role r) {
      return size_t(std::find(vertex_roles_.begin(), vertex_roles_.end(), r) - vertex_roles_.begin());
    };
    const size_t ix = role_index(kX), iy = role_index(kY), iz = role_index(kZ);
    const bool float_xyz = e.props[ix].type == Type::f32 && e.props[iy].type == Type::f32 &&
                           e.props[iz].type == Type::f32;
    const size_t n = size_t(e.count);
    if (float_xyz && stride == 12 && offsets[ix] == 0 && offsets[iy] == 4 && offsets[iz] == 8) {
      std::memcpy(mesh_.positions.data(), p, 12 * n);  // exactly x y z: the arrays match byte for byte
    } else if (float_xyz && offsets[iy] == offsets[ix] + 4 && offsets[iz] == offsets[ix] + 8) {
      for (size_t v = 0; v < n; ++v) std::memcpy(&mesh_.positions[v], p + v * stride + offsets[ix], 12);
    } else {
      for (size_t v = 0; v < n; ++v)
        for (int r = kX; r <= kZ; ++r) {
          const size_t i = role_index(Role(r));
          store_vertex(v, Role(r), float(load_number(p + v * stride + offsets[i], e.props[i].type, false)));
        }
    }
    if (has_normals_)
      for (size_t v = 0; v < n; ++v)
        for (int r = kNx; r <= kNz; ++r) {
          const size_t i = role_index(Role(r));
          store_vertex(v, Role(r), float(load_number(p + v * stride + offsets[i], e.props[i].type, false)));
        }
    p += n * stride;
  }

  /// Native-endian faces made of one list with a one-byte count and 4-byte indices: triangles
  /// are copied, larger faces fanned.
  const char* read_faces_fast(const Element& e, const char* p) {
    const Property& q = e.props[0];
    const char* const end = data_ + size_;
    const bool signed_count = q.count_type == Type::i8, signed_index = q.type == Type::i32;
    const uint32_t nv = uint32_t(vertex_->count);
    std::vector<uint32_t>& out = mesh_.indices;
    size_t k = out.size();
    out.resize(k + 3 * size_t(e.count));
    for (uint64_t f = 0; f < e.count; ++f) {
      if (p >= end) fail_truncated(e, f);
      const int64_t count = signed_count ? int64_t(int8_t(*p)) : int64_t(uint8_t(*p));
      if (count < 3) fail_count(f, count);
      if (size_t(end - p - 1) < 4 * size_t(count)) fail_truncated(e, f);
      if (count == 3) {
        uint32_t tri[3];
        std::memcpy(tri, p + 1, 12);
        if (tri[0] >= nv || tri[1] >= nv || tri[2] >= nv) {
          for (uint32_t v : tri)
            if (v >= nv) fail_index(f, signed_index ? int64_t(int32_t(v)) : int64_t(v));
        }
        std::memcpy(&out[k], tri, 12);
        k += 3;
      } else {
        out.resize(k);
        const char* items = p + 1;
        add_face(f, count, [&](int64_t i) {
          uint32_t v;
          std::memcpy(&v, items + 4 * size_t(i), 4);
          return signed_index ? int64_t(int32_t(v)) : int64_t(v);
        });
        k = out.size();
        out.resize(k + 3 * size_t(e.count - f - 1));  // room for the remaining faces as triangles
      }
      p += 1 + 4 * size_t(count);
    }
    out.resize(k);
    return p;
  }

  // --- ascii ---------------------------------------------------------------------------------

  /// Next blank-separated token at `offset`, counting lines; empty at the end of the file.
  std::string_view next_token(size_t& offset, size_t& line) const {
    while (offset < size_ && is_space(data_[offset])) {
      if (data_[offset] == '\n') ++line;
      ++offset;
    }
    const size_t start = offset;
    while (offset < size_ && !is_space(data_[offset])) ++offset;
    return std::string_view(data_ + start, offset - start);
  }

  static bool parses_as_double(std::string_view s) {
    if (!s.empty() && s[0] == '+') s.remove_prefix(1);
    double d;
    auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), d);
    return end == s.data() + s.size() && (ec == std::errc() || ec == std::errc::result_out_of_range);
  }

  double parse_number(std::string_view s, Type t, size_t line) const {
    if (is_integer(t)) return double(parse_integer(s, line));
    std::string_view digits = s;
    if (!digits.empty() && digits[0] == '+') digits.remove_prefix(1);
    double d = 0.0;
    float f = 0.0f;
    std::from_chars_result r =
        t == Type::f32 ? std::from_chars(digits.data(), digits.data() + digits.size(), f)
                       : std::from_chars(digits.data(), digits.data() + digits.size(), d);
    if (digits.empty() || r.ptr != digits.data() + digits.size() ||
        (r.ec != std::errc() && r.ec != std::errc::result_out_of_range))
      fail_line(line, cat("'", s, "' is not a number"));
    if (r.ec == std::errc::result_out_of_range) d = std::strtod(std::string(digits).c_str(), nullptr);  // inf or 0
    else if (t == Type::f32) d = f;
    return d;
  }

  int64_t parse_integer(std::string_view s, size_t line) const {
    std::string_view digits = s;
    if (!digits.empty() && digits[0] == '+') digits.remove_prefix(1);
    int64_t v = 0;
    auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), v);
    if (digits.empty() || ec != std::errc() || end != digits.data() + digits.size())
      fail_line(line, cat("'", s, "' is not ", parses_as_double(digits) ? "an integer" : "a number"));
    return v;
  }

  void read_ascii(const Element& e, size_t& offset, size_t& line) {
    auto token = [&](uint64_t item) {
      const std::string_view t = next_token(offset, line);
      if (t.empty())
        throw Error(cat(path_, ": truncated: ", e.name, " ", item, " ends past the end of the file at line ", line));
      return t;
    };
    if (e.props.empty()) return;  // items without properties take no bytes
    std::vector<int64_t> face;
    for (uint64_t item = 0; item < e.count; ++item) {
      for (size_t i = 0; i < e.props.size(); ++i) {
        const Property& q = e.props[i];
        if (!q.list) {
          const std::string_view t = token(item);
          const double value = parse_number(t, q.type, line);
          if (&e == vertex_ && vertex_roles_[i] != kNone) store_vertex(item, vertex_roles_[i], float(value));
          continue;
        }
        const std::string_view count_token = token(item);
        const int64_t count = parse_integer(count_token, line);
        const bool indices = &e == face_ && int(i) == face_list_;
        if (indices && count < 3) fail_count(item, count);
        if (count < 0) fail_line(line, cat(e.name, " ", item, " has a list of ", count, " items"));
        if (indices) {
          face.clear();
          for (int64_t k = 0; k < count; ++k) {
            const std::string_view t = token(item);
            face.push_back(parse_integer(t, line));
          }
          add_face(item, count, [&](int64_t k) { return face[size_t(k)]; });
        } else {
          for (int64_t k = 0; k < count; ++k) {
            const std::string_view t = token(item);
            parse_number(t, q.type, line);
          }
        }
      }
    }
  }

  const std::string& path_;
  const char* data_;
  size_t size_;
  Format format_ = Format::ascii;
  std::vector<Element> elements_;
  const Element* vertex_ = nullptr;
  const Element* face_ = nullptr;
  std::vector<Role> vertex_roles_;
  bool has_normals_ = false;
  int face_list_ = -1;
  size_t header_lines_ = 0;
  size_t data_begin_ = 0;
  TriangleMesh mesh_;
};

}  // namespace

void load_ply(const std::string& path, Scene& scene) {
  const MappedFile file(path);
  TriangleMesh mesh = PlyReader(path, file.data(), file.size()).read();
  if (mesh.indices.empty()) return;
  mesh.name = std::filesystem::path(path).stem().string();
  try {
    scene.add_mesh(std::move(mesh));
  } catch (const Error& e) {
    throw Error(cat(path, ": ", e.what()));
  }
}

}  // namespace rp
