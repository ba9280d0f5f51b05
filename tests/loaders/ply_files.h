#pragma once
// PLY files for the loader tests, written byte by byte in every format (ASCII, binary little
// and big endian): a writer and a unit cube in several element layouts.

#include <bit>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace rp::test {

enum class PlyFormat { ascii, little_endian, big_endian };

/// Writes a PLY file: header lines, then values typed as declared.
class PlyWriter {
 public:
  explicit PlyWriter(PlyFormat f) : format_(f) {}

  PlyWriter& header(const std::string& line) {
    header_ += line + "\n";
    return *this;
  }
  /// One value of PLY type `type` (ascii: a token; binary: its bytes in the file's byte order).
  PlyWriter& put(const std::string& type, double v) {
    if (format_ == PlyFormat::ascii) {
      char buf[64];
      if (type == "float" || type == "float32")
        std::snprintf(buf, sizeof buf, "%.9g ", v);
      else if (type == "double" || type == "float64")
        std::snprintf(buf, sizeof buf, "%.17g ", v);
      else
        std::snprintf(buf, sizeof buf, "%lld ", static_cast<long long>(v));
      body_ += buf;
      return *this;
    }
    if (type == "char" || type == "int8") bytes(int8_t(v));
    else if (type == "uchar" || type == "uint8") bytes(uint8_t(v));
    else if (type == "short" || type == "int16") bytes(int16_t(v));
    else if (type == "ushort" || type == "uint16") bytes(uint16_t(v));
    else if (type == "int" || type == "int32") bytes(int32_t(v));
    else if (type == "uint" || type == "uint32") bytes(uint32_t(int64_t(v)));
    else if (type == "float" || type == "float32") bytes(float(v));
    else bytes(v);
    return *this;
  }
  /// Ends an element item (a new line in ascii).
  PlyWriter& end_item() {
    if (format_ == PlyFormat::ascii && !body_.empty() && body_.back() == ' ') body_.back() = '\n';
    return *this;
  }
  std::string str() const {
    const char* name = format_ == PlyFormat::ascii           ? "ascii"
                       : format_ == PlyFormat::little_endian ? "binary_little_endian"
                                                             : "binary_big_endian";
    return std::string("ply\nformat ") + name + " 1.0\n" + header_ + "end_header\n" + body_;
  }

 private:
  template <typename T>
  void bytes(T v) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof v);
    const bool big = format_ == PlyFormat::big_endian;
    if (big == (std::endian::native == std::endian::little)) std::reverse(b, b + sizeof(T));
    body_.append(b, sizeof(T));
  }

  PlyFormat format_;
  std::string header_, body_;
};

const std::vector<Vec3f> kCubeVertices = {{-1.5f, -1, 0.25f}, {2.25f, -1, 0.25f}, {2.25f, 3, 0.25f},
                                          {-1.5f, 3, 0.25f},  {-1.5f, -1, 4.5f},  {2.25f, -1, 4.5f},
                                          {2.25f, 3, 4.5f},   {-1.5f, 3, 4.5f}};
const std::vector<Vec3f> kCubeNormals = {{-0.5f, -0.5f, -0.5f}, {0.5f, -0.5f, -0.5f}, {0.5f, 0.5f, -0.5f},
                                         {-0.5f, 0.5f, -0.5f},  {-0.5f, -0.5f, 0.5f}, {0.5f, -0.5f, 0.5f},
                                         {0.5f, 0.5f, 0.5f},    {-0.5f, 0.5f, 0.5f}};
/// Five quads and one quad given as two triangles (faces 2 and 3); the last face is a quad.
const std::vector<std::vector<int>> kCubeFaces = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5}, {0, 5, 4},
                                                  {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
/// The fan of each face, as the loader must give it.
const std::vector<uint32_t> kCubeIndices = {0, 3, 2, 0, 2, 1, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                            1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7};

enum class CubeLayout {
  plain,    ///< float x y z; list uchar int vertex_indices (the fast path)
  rich,     ///< normals, colours, a list on vertices, an edge element, a face flag after the list
  doubles,  ///< an int before double x y z; list int int vertex_index
  offset,   ///< float confidence before float x y z; list uchar uint vertex_indices
};

inline std::string cube_ply(PlyFormat f, CubeLayout layout) {
  PlyWriter w(f);
  w.header("comment a cube").header("obj_info written by loaders_test");
  w.header("element vertex 8");
  switch (layout) {
    case CubeLayout::plain: w.header("property float x").header("property float y").header("property float z"); break;
    case CubeLayout::rich:
      w.header("property float32 x").header("property float32 y").header("property float32 z");
      w.header("property float nx").header("property float ny").header("property float nz");
      w.header("property uchar red").header("property list uchar float weights").header("property uint8 green");
      break;
    case CubeLayout::doubles:
      w.header("property int id").header("property double x").header("property double y").header("property double z");
      break;
    case CubeLayout::offset:
      w.header("property float confidence").header("property float x").header("property float y");
      w.header("property float z");
      break;
  }
  if (layout == CubeLayout::rich) w.header("element edge 2").header("property int v1").header("property int v2");
  w.header(cat("element face ", kCubeFaces.size()));
  switch (layout) {
    case CubeLayout::plain: w.header("property list uchar int vertex_indices"); break;
    case CubeLayout::rich: w.header("property list uint8 uint32 vertex_indices").header("property uchar flags"); break;
    case CubeLayout::doubles: w.header("property list int int vertex_index"); break;
    case CubeLayout::offset: w.header("property list uchar uint vertex_indices"); break;
  }
  for (size_t i = 0; i < kCubeVertices.size(); ++i) {
    const Vec3f& v = kCubeVertices[i];
    const char* type = layout == CubeLayout::doubles ? "double" : "float";
    if (layout == CubeLayout::doubles) w.put("int", double(i));
    if (layout == CubeLayout::offset) w.put("float", 0.5);
    w.put(type, v.x).put(type, v.y).put(type, v.z);
    if (layout == CubeLayout::rich) {
      const Vec3f& n = kCubeNormals[i];
      w.put("float", n.x).put("float", n.y).put("float", n.z).put("uchar", 200);
      w.put("uchar", double(i % 3));
      for (size_t k = 0; k < i % 3; ++k) w.put("float", 0.125 * double(k));
      w.put("uchar", 7);
    }
    w.end_item();
  }
  if (layout == CubeLayout::rich)
    for (int e = 0; e < 2; ++e) w.put("int", e).put("int", e + 1).end_item();
  for (const std::vector<int>& face : kCubeFaces) {
    const char* count = layout == CubeLayout::doubles ? "int" : "uchar";
    const char* index = layout == CubeLayout::doubles ? "int" : (layout == CubeLayout::plain ? "int" : "uint");
    w.put(count, double(face.size()));
    for (int v : face) w.put(index, v);
    if (layout == CubeLayout::rich) w.put("uchar", 1);
    w.end_item();
  }
  return w.str();
}

inline const char* name_of(PlyFormat f) {
  return f == PlyFormat::ascii ? "ascii" : f == PlyFormat::little_endian ? "little_endian" : "big_endian";
}

}  // namespace rp::test
