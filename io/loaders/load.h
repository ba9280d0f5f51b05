#pragma once
/// Scene files: OBJ (+MTL) through tinyobjloader, PLY (ascii, binary little and big endian),
/// JSON scenes, glTF 2.0 (.gltf, .glb, with node animation) through tinygltf.

#include <optional>
#include <string>

#include "core/scene.h"
#include "io/loaders/animation.h"

namespace rp {

/// Loads `path` by its extension (.obj, .ply, .json, .gltf, .glb, case-insensitive), or the
/// embedded default scene for the name "default". The scene has no camera unless the file
/// gives one; lights are added when the file has none (a key light above the front and a
/// directional fill, placed by the scene's up axis) so that a render shows the model.
/// `up_axis` (0 x, 1 y, 2 z), when given, is the scene's up axis whatever the file says
/// (Scene::set_up_axis). Throws rp::Error with the file and line (or byte offset, or JSON
/// path) of the first problem. An animated file (glTF) loads at its rest pose, the nodes' own
/// translation, rotation and scale, which need not be its pose at 0 s: load_animated_scene's
/// scene, without the animation.
Scene load_scene(const std::string& path, std::optional<int> up_axis = std::nullopt);

/// load_scene's scene and the file's animation (io/loaders/animation.h): a glTF's, empty for
/// every other format. What an animated node places is in the scene as the animation can move
/// it: its meshes as instanced meshes, each placement an instance (however many nodes place
/// the mesh), its lights and camera as the file's; SceneAnimation::apply poses the scene at a
/// time. Default lights, for a file without lights, are placed from the rest pose's bounds.
/// Throws as load_scene.
AnimatedScene load_animated_scene(const std::string& path, std::optional<int> up_axis = std::nullopt);

/// The extension of the file name in `path` (std::filesystem's: from its last '.', none for a
/// name that only starts with one), lower-cased: "a/Bunny.OBJ" -> ".obj", "a.b/c" -> "".
std::string lower_extension(const std::string& path);

/// Appends the triangles of an OBJ file (and its MTL materials, when found) to `scene`.
void load_obj(const std::string& path, Scene& scene);

/// Appends the triangles of a PLY file to `scene`.
void load_ply(const std::string& path, Scene& scene);

/// Appends the materials, lights and objects of a JSON scene file to `scene` and sets its
/// camera when the file has one (the format: the top of io/loaders/json_scene.cpp). Adds
/// no default lights (load_scene does). Throws rp::Error naming the file, the JSON path and
/// the value of the first problem.
void load_json_scene(const std::string& path, Scene& scene);

/// Appends the meshes, instances, lights, materials and (first) camera of a glTF 2.0 file's
/// default scene to `scene`, at its rest pose, and returns its animation, whose targets are
/// those instances, lights and camera (the mapping, what is animated and what is refused: the
/// top of io/loaders/gltf.cpp). Adds no default lights (load_scene does). Throws rp::Error
/// naming the file and the JSON path of the first problem.
SceneAnimation load_gltf(const std::string& path, Scene& scene);

}  // namespace rp
