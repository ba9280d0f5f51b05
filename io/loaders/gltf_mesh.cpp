/// glTF accessors and primitives (io/loaders/gltf_reader.h): an accessor's elements,
/// checked against their bufferView and buffer, and a mesh's triangle primitives as one
/// TriangleMesh.

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "base/error.h"
#include "io/loaders/gltf_reader.h"

namespace rp {
namespace {

/// The accessor type of elements of 1 to 4 components.
constexpr const char* kTypeNames[] = {"", "SCALAR", "VEC2", "VEC3", "VEC4"};

/// The normalized integer component at `p`, mapped to a number as glTF 2.0 maps it (its
/// "Animations" section): signed max(c / (2^(n-1) - 1), -1), unsigned c / (2^n - 1).
template <typename Int>
double unit_number(const unsigned char* p) {
  Int c;
  std::memcpy(&c, p, sizeof c);
  return std::max(double(c) / double(std::numeric_limits<Int>::max()), -1.0);
}

/// The component at `p` of `component_type` as a number: a float as it is, an integer as a
/// normalized one (unit_number).
double number(const unsigned char* p, int component_type) {
  switch (component_type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
      return unit_number<int8_t>(p);
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
      return unit_number<uint8_t>(p);
    case TINYGLTF_COMPONENT_TYPE_SHORT:
      return unit_number<int16_t>(p);
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
      return unit_number<uint16_t>(p);
    default: {
      float f;
      std::memcpy(&f, p, 4);
      return f;
    }
  }
}

}  // namespace

GltfReader::View GltfReader::view(int a, const std::string& use, int type,
                                  std::initializer_list<int> component_types) const {
  const tinygltf::Accessor& acc = at(m_.accessors, a, use);
  const std::string ap = cat("$.accessors[", a, "]");
  // Refused where the reader reads one only: a model may have sparse accessors elsewhere
  // (morph targets), which it does not read.
  if (acc.sparse.isSparse) fail(ap + ".sparse", "sparse accessors are not supported");
  const uint64_t components = type == TINYGLTF_TYPE_SCALAR ? 1 : type == TINYGLTF_TYPE_VEC3 ? 3 : 4;
  if (acc.type != type) fail(ap + ".type", cat(use, " needs ", kTypeNames[components], " elements"));
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
  return {buffer.data.data() + bv.byteOffset + offset, size_t(count), size_t(stride), size_t(components),
          acc.componentType};
}

std::vector<Vec3f> GltfReader::vectors(const View& v) const {
  std::vector<Vec3f> out(v.count);
  for (size_t i = 0; i < v.count; ++i) std::memcpy(&out[i], v.data + i * v.stride, 12);
  return out;
}

std::vector<double> GltfReader::numbers(const View& v) const {
  std::vector<double> out(v.count * v.components);
  const size_t size = size_t(tinygltf::GetComponentSizeInBytes(uint32_t(v.component_type)));
  for (size_t i = 0; i < v.count; ++i)
    for (size_t c = 0; c < v.components; ++c)
      out[i * v.components + c] = number(v.data + i * v.stride + c * size, v.component_type);
  return out;
}

std::vector<uint32_t> GltfReader::indices(const View& v) const {
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

TriangleMesh GltfReader::convert(int i) {
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
    const std::vector<Vec3f> positions =
        vectors(view(position->second, ap, TINYGLTF_TYPE_VEC3, {TINYGLTF_COMPONENT_TYPE_FLOAT}));
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
          fail(ip, cat("element ", c, ": ", corners[c], " is not a vertex index (the primitive has ", positions.size(),
                       " vertices)"));
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
  if (!face_materials.empty() &&
      std::all_of(face_materials.begin(), face_materials.end(), [&](uint32_t m) { return m == face_materials[0]; })) {
    out.material = face_materials[0];
  } else {
    out.face_materials = std::move(face_materials);
  }
  return out;
}

std::vector<uint32_t> GltfReader::triangulate(const std::vector<uint32_t>& c, int mode) {
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

}  // namespace rp
