#include "io/loaders/load.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <utility>

#include "base/error.h"
#include "base/text.h"

namespace rp {

/// Lights for a file that brings none, placed from the scene bounds (centre c, radius
/// r = half the diagonal) in the scene's up frame (up_frame: Y up seen from +Z, as the real
/// models are):
/// - a key PointLight at c + (0.5 right + 1.5 up + 2 front) r, above the front and a little
///   to the right, with an intensity that gives an irradiance of 0.8 at c (0.8 d^2);
/// - a directional fill from the upper left front, direction normalize(right - up - front),
///   irradiance 0.3.
static void add_default_lights(Scene& scene) {
  const Box3f b = scene.bounds();
  const Vec3f c = b.empty() ? Vec3f(0.0f) : b.center();
  float r = b.empty() ? 0.0f : 0.5f * length(b.extent());
  if (!(r > 0.0f) || !std::isfinite(r)) r = 1.0f;
  const UpFrame f = up_frame(scene.up_axis());
  const Vec3f offset = (f.right * 0.5f + f.up * 1.5f + f.front * 2.0f) * r;
  Vec3f position = c + offset;  // kept within the coordinate range of core/ray.h
  for (int a = 0; a < 3; ++a) position[a] = std::clamp(position[a], -kMaxCoordinate, kMaxCoordinate);
  scene.add_light(PointLight{.position = position, .intensity = Vec3f(0.8f * dot(offset, offset))});
  scene.add_light(DirectionalLight{.direction = normalize(f.right - f.up - f.front), .irradiance = Vec3f(0.3f)});
}

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return char(std::tolower(ch)); });
  return ext;
}

Scene load_scene(const std::string& path, std::optional<int> up_axis) {
  return std::move(load_animated_scene(path, up_axis).scene);
}

AnimatedScene load_animated_scene(const std::string& path, std::optional<int> up_axis) {
  AnimatedScene out;
  if (path == "default") {
    out.scene = make_default_scene();
    return out;
  }

  const std::string lower = lower_extension(path);

  Scene& scene = out.scene;
  if (lower == ".json") {
    load_json_scene(path, scene);  // needs at least one object, of any kind
  } else {
    if (lower == ".obj")
      load_obj(path, scene);
    else if (lower == ".ply")
      load_ply(path, scene);
    else if (lower == ".gltf" || lower == ".glb")
      out.animation = load_gltf(path, scene);
    else
      throw Error(cat(path, ": unknown scene format '", std::filesystem::path(path).extension().string(),
                      "' (.obj, .ply, .json, .gltf, .glb)"));
    RP_CHECK(scene.triangle_count() > 0, path, ": the file has no triangles");
  }
  if (up_axis) scene.set_up_axis(*up_axis);
  if (scene.point_lights().empty() && scene.directional_lights().empty()) add_default_lights(scene);
  // Zero-area triangles are kept (the numbering stays the file's) but can never be hit.
  if (const size_t degenerate = scene.degenerate_triangle_count(); degenerate > 0)
    warn(cat(path, ": ", degenerate, " zero-area triangle", degenerate == 1 ? "" : "s", " kept; no ray can hit ",
             degenerate == 1 ? "it" : "them"));
  return out;
}

}  // namespace rp
