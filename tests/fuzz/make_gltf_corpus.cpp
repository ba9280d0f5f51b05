/// Writes the glTF seeds of corpus/fuzz_gltf/ into the folder given as its argument, from the
/// same builders the loader tests use (tests/support/gltf_files.h): valid files in the three
/// forms (data URIs, an external buffer, .glb), with a hierarchy, instancing, every index
/// type, strips and fans, cameras and lights, an animation of every interpolation, and every
/// hostile case (and a few animations, skins and morph weights to refuse). Run by hand when the
/// builders change (the corpus is kept in the repository):
///   build/tests/fuzz/rp_make_gltf_corpus tests/fuzz/corpus/fuzz_gltf

#include <cstdio>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>

#include "tests/support/animated_gltf.h"
#include "tests/support/gltf_files.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: rp_make_gltf_corpus FOLDER\n");
    return 2;
  }
  namespace fs = std::filesystem;
  using rp::test::GltfCase;
  using rp::test::GltfForm;
  const std::string dir = argv[1];
  fs::create_directories(dir);
  std::vector<GltfCase> cases = rp::test::hostile_gltf_cases();
  const tinygltf::Model hierarchy = rp::test::hierarchy_gltf().model;
  cases.push_back({"valid-hierarchy.gltf", hierarchy, GltfForm::embedded, {}, 0});
  cases.push_back({"valid-hierarchy.glb", hierarchy, GltfForm::binary, {}, 0});
  cases.push_back({"valid-external.gltf", hierarchy, GltfForm::external, {}, 0});
  cases.push_back({"valid-camera-lights.glb", rp::test::camera_and_lights_gltf().model, GltfForm::binary, {}, 0});
  cases.push_back({"valid-one-triangle.gltf", rp::test::one_triangle().model, GltfForm::embedded, {}, 0});
  const tinygltf::Model animated = rp::test::animated_scene().model;
  cases.push_back({"valid-animated.gltf", animated, GltfForm::embedded, {}, 0});
  cases.push_back({"valid-animated.glb", animated, GltfForm::binary, {}, 0});
  using nlohmann::json;
  const std::pair<const char*, std::function<void(json&)>> refused[] = {
      {"bad-animation-count.gltf",
       [](json& d) { d["accessors"][d["animations"][0]["samplers"][3]["input"].get<int>()]["count"] = 2; }},
      {"bad-animation-interpolation.gltf",
       [](json& d) { d["animations"][0]["samplers"][2]["interpolation"] = "LINEAR"; }},
      {"bad-animation-weights.gltf", [](json& d) { d["animations"][0]["channels"][0]["target"]["path"] = "weights"; }},
      {"bad-animation-node.gltf", [](json& d) { d["animations"][0]["channels"][1]["target"].erase("node"); }},
      {"bad-skin.gltf",
       [](json& d) {
         d["skins"] = {{{"joints", {4}}}};
         d["nodes"][4]["skin"] = 0;
       }},
      {"bad-morph-weights.gltf",
       [](json& d) {
         d["meshes"][1]["primitives"][0]["targets"] = {{{"POSITION", 2}}};
         d["meshes"][1]["weights"] = {0.5};
       }},
  };
  for (const auto& [name, patch] : refused) cases.push_back({name, animated, GltfForm::embedded, patch, 0});
  for (const GltfCase& c : cases) {
    try {
      std::printf("%s\n", rp::test::write_case(c, dir).c_str());
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s: %s\n", c.name.c_str(), e.what());
      return 1;
    }
  }
  fs::remove(fs::path(dir) / "valid-external.bin");  // the fuzz target writes it beside each input
  return 0;
}
