#pragma once
/// The glTF JSON check (io/loaders/gltf_check.cpp): a glTF's JSON document checked before
/// tinygltf 2.7 reads it, for the glTF reader (io/loaders/gltf.cpp), which maps what
/// tinygltf reads onto the Scene. tinygltf turns most wrong values into defaults without a
/// word and builds every object the JSON lists, however many; this check refuses both first.

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace rp {

/// The most bytes of a glTF file, and of each external buffer it names: 2 GiB.
inline constexpr uint64_t kMaxGltfBytes = uint64_t(2) << 30;

/// The memory tinygltf may take to read a glTF: at least kGltfMemoryFloor, and
/// kGltfMemoryPerInputByte bytes per byte of input (the file, a GLB's BIN chunk included, and
/// the byteLength of each external buffer).
inline constexpr uint64_t kGltfMemoryFloor = uint64_t(256) << 20;
inline constexpr uint64_t kGltfMemoryPerInputByte = 32;

/// What tinygltf's JSON DOM (nlohmann-json's) is counted to take per byte of JSON text.
inline constexpr uint64_t kGltfDomBytesPerJsonByte = 12;

/// The most a rotation (a node's, an animation keyframe's) may differ from a unit quaternion in
/// length: glTF-Validator's tolerance for ROTATION_NON_UNIT (unitLengthThresholdVec4, just
/// above the error of a quaternion quantised to signed bytes).
inline constexpr double kUnitQuaternionTolerance = 0.00769;

/// What is wrong with rotation `q` (x, y, z, w) as glTF takes it: "a zero quaternion is no
/// rotation", or its length outside 1 +- kUnitQuaternionTolerance, with that length; nothing
/// when it is a rotation. The length is found from the components divided by the largest, so
/// that no square overflows.
std::optional<std::string> rotation_problem(std::span<const double> q);

/// A buffer the glTF names by a file URI, resolved inside the glTF's folder.
struct GltfBufferFile {
  size_t index;          ///< in $.buffers
  std::string uri;       ///< as written
  std::string path;      ///< what tinygltf asks for: its base folder joined with the decoded URI
  std::string file;      ///< what is read: that path with the URI's "." and ".." segments removed
  uint64_t byte_length;  ///< the buffer's byteLength, which the file must have
};

/// The glTF file whose JSON is checked, as the check needs to know it.
struct GltfSource {
  std::string path;                   ///< the file as named, the start of every message
  std::string base;                   ///< the folder tinygltf is given ("." or "/" at least)
  bool binary = false;                ///< a GLB: buffer 0 may be its BIN chunk
  std::optional<uint64_t> bin_bytes;  ///< a GLB's BIN chunk length, in bytes, when it has one
  uint64_t file_bytes = 0;            ///< the whole file's size, in bytes
  uint64_t json_bytes = 0;            ///< the JSON text's size, in bytes (a GLB's first chunk)
};

/// Checks glTF JSON document `doc` of `source` and returns its external buffers (those whose
/// URI is not a data URI), in $.buffers order. Throws rp::Error, one line of the form
/// "<path>: <JSON path>: <what is wrong>", for the first problem found (the memory estimate
/// as soon as the sections are known to be arrays of objects, then element by element):
/// - a value of the sections the reader uses (asset, scenes, nodes, meshes, accessors,
///   bufferViews, buffers, materials, cameras, KHR_lights_punctual lights, animations) of the
///   wrong JSON type, outside glTF 2.0's range or missing when required: an index naming no
///   element (a node's skin, an animation channel's sampler or target node among them), a
///   negative offset, a count or length of 0, a non-number in a transform or in morph
///   weights, a factor outside [0, 1], a rotation whose length is not within 0.00769 of 1
///   (glTF-Validator's tolerance), an unknown componentType, accessor, camera or light type,
///   animation path or interpolation;
/// - a buffer with no URI outside a GLB's buffer 0, or longer than the GLB's BIN chunk;
/// - a buffer URI that, %-decoded as tinygltf decodes it, is absolute, holds a NUL byte or
///   leads out of `source.base` as written ("../x.bin") or once symbolic links are followed
///   (realpath(3); a link swapped in after this check is not caught);
/// - objects that would make tinygltf take more memory than allowed: the estimate is
///   kGltfDomBytesPerJsonByte per byte of JSON plus, for every kind of object tinygltf builds
///   (scenes, nodes, meshes, primitives, accessors, ..., and one tinygltf::Value per JSON value
///   under "extras" or "extensions"), its count times sizeof of its tinygltf type; the budget
///   is kGltfMemoryPerInputByte per byte of input, at least kGltfMemoryFloor. The message
///   names the kind that takes the most: "<path>: $.nodes: 1000000 nodes would make tinygltf
///   take about 640 MiB, more than the 546 MiB allowed for 17889263 bytes of input (32 bytes
///   per byte of input, at least 256 MiB)".
std::vector<GltfBufferFile> check_gltf_json(const GltfSource& source, const nlohmann::json& doc);

/// A string from a glTF file as the glTF messages quote it: in double quotes, cut and made
/// printable by rp::printable.
std::string gltf_quoted(std::string_view text);

}  // namespace rp
