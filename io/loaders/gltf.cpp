/// glTF 2.0 scenes (.gltf with external or data-URI buffers, .glb) through tinygltf 2.7
/// (io/loaders/tinygltf_impl.cpp), mapped onto the Scene:
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
///   world coordinates; a mesh several nodes place, or any node the animation moves (below),
///   is stored once in its own coordinates and each node is an instance (Scene::add_instance);
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
/// - animations (io/loaders/animation.h), read into the SceneAnimation load_gltf returns,
///   the scene itself at its rest pose (the nodes' own values): every channel whose
///   target.path is "translation", "rotation" or "scale"; every animation of the file plays
///   at once from 0 s, each value before a sampler's first keyframe its first, after its last
///   its last; the value a channel gives replaces that property of the node, which keeps its
///   own values of the others. Samplers: LINEAR (rotations by slerp along the shorter arc),
///   STEP, CUBICSPLINE (glTF's Appendix C: in-tangent, value, out-tangent per keyframe,
///   tangents times the keyframes' interval; a rotation's result normalised). Input accessors
///   of floats (SCALAR, 5126), finite and strictly increasing; outputs of VEC3 floats for a
///   translation or scale and VEC4 for a rotation, of floats or of normalized integers (5120,
///   5121, 5122, 5123: "normalized": true, mapped as glTF says), as many elements as
///   keyframes (three times as many for CUBICSPLINE), every number finite, every rotation
///   value a unit quaternion within 0.00769 (then normalised). What a node the animation moves
///   places (the node animated, or below an animated node) moves with it: its meshes as
///   instances (Scene::set_transform), its KHR_lights_punctual lights (Scene::set_light), the
///   camera (Scene::set_camera), each node's placement composed parent * child in double as
///   above;
/// - external buffers only from the glTF's folder and below: a buffer's URI, %-decoded as
///   tinygltf decodes it, is a relative path that must stay inside that folder both as written
///   ("../x.bin", "..%2Fx.bin" and "/etc/x" are refused, "sub/../x.bin" is read) and with every
///   symbolic link followed (realpath(3) against the folder's canonical path: a link inside the
///   folder to a file outside it is refused, one to a file inside it is read).
///
/// Refused with one line naming the file and the JSON path, first by the JSON check before
/// tinygltf reads the JSON (check_gltf_json, io/loaders/gltf_check.h, lists each): values
/// of the sections raypack uses that have the wrong type or lie outside glTF's range (indices
/// naming nothing, negative offsets, counts or lengths of 0, non-numbers in a transform,
/// factors outside [0, 1], a rotation that is not a unit quaternion, an unknown componentType,
/// accessor, camera or light type, a required property missing), since
/// tinygltf turns most of them into defaults without a word; buffer URIs leading out of the
/// glTF's folder; and objects that would take tinygltf far more memory than the file (below).
/// Then, what cannot be animated or drawn as the file means it: a node with a "skin"
/// ("$.nodes[3].skin: skinned meshes are not supported"), morph targets of a non-zero weight
/// (the node's "weights", else its mesh's: "$.meshes[0].weights[1]: 0.5: morph targets of a
/// non-zero weight are not supported"; targets of weight 0 change nothing and are not read),
/// a channel of target.path "weights" ("morph-target animation is not supported"), a channel
/// on a node placed by a "matrix" (glTF animates translation, rotation and scale only), two
/// channels on one property of one node (in one animation or two: as all play at once, which
/// would win is refused rather than chosen), a sampler breaking the rules above, and a node
/// the animation moves whose rest transform is singular (its mesh could not be placed).
/// Then: Draco-compressed primitives without an uncompressed fallback, sparse accessors that
/// a primitive or an animation sampler reads (sparse ones nothing reads, a morph target's, are
/// left alone), accessors whose elements do not fit their bufferView and buffer (bad offsets,
/// strides, absurd counts: checked before anything is allocated for them), indices that name no vertex or are not of
/// an unsigned integer type, positions that are not 3 floats or lie outside the coordinate
/// range, node cycles and nodes with two parents, non-affine matrices, buffers missing or
/// unreadable (a device, a directory: io/input_file.h's rule) or of another size than
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
/// This file is the tinygltf glue (file callbacks, GLB chunks, tinygltf's messages); the JSON
/// check before it is io/loaders/gltf_check.cpp, the mapping onto the Scene after it
/// io/loaders/gltf_reader.h (the node hierarchy in gltf_scene.cpp, accessors and
/// primitives in gltf_mesh.cpp, animations in gltf_animation.cpp).

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

#include "base/error.h"
#include "base/text.h"
#include "io/input_file.h"
#include "io/json_text.h"
#include "io/loaders/gltf_check.h"
#include "io/loaders/gltf_reader.h"
#include "io/loaders/load.h"
#include "io/loaders/tinygltf_config.h"
#include "io/memory_reserve.h"

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

/// The first line of a message tinygltf built of several.
std::string first_line(const std::string& s) {
  std::string line = s.substr(0, s.find('\n'));
  while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '.')) line.pop_back();
  return line.empty() ? std::string("tinygltf refused it") : one_line(line);
}

}  // namespace

SceneAnimation load_gltf(const std::string& path, Scene& scene) {
  const MappedFile file(path);
  if (file.size() > kMaxGltfBytes)
    throw Error(cat(path, ": ", file.size(), " bytes, more than the ", kMaxGltfBytes, " a glTF file may have"));
  if (file.size() == 0) throw Error(cat(path, ": empty file"));
  const std::string_view bytes(file.data(), file.size());
  const bool binary = bytes.substr(0, 4) == "glTF" || lower_extension(path) == ".glb";
  const GlbChunks glb = binary ? glb_chunks(path, bytes) : GlbChunks{bytes, std::nullopt};
  check_json_depth(path, glb.json);  // nlohmann's parser and tinygltf's recurse
  // Outlives both JSON documents (this one and tinygltf's): see io/memory_reserve.h.
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
  return GltfReader(path, model, scene).read();
}

}  // namespace rp
