#pragma once
// glTF files the loader tests write into the scratch folder (scratch.h), and the message a
// load of one fails with.

#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>

#include "io/loaders/load.h"
#include "scratch.h"
#include "tests/support/error_of.h"
#include "tests/support/gltf_files.h"

namespace rp::test {

/// `model` written as `name` in `form` in the scratch folder; its path.
inline std::string written(const tinygltf::Model& model, const std::string& name, GltfForm form,
                           const std::function<void(nlohmann::json&)>& patch = {}) {
  const std::filesystem::path path = scratch() / name;
  std::filesystem::create_directories(path.parent_path());
  write_gltf(model, path.string(), form, patch);
  return path.string();
}

/// what() of load_scene(path)'s rp::Error with the scratch folder's path removed, or "no error".
inline std::string error_loading(const std::string& path) {
  std::string s = error_of([&] { load_scene(path); });
  const std::string dir = scratch().string() + "/";
  for (size_t at = s.find(dir); at != std::string::npos; at = s.find(dir)) s.erase(at, dir.size());
  return s;
}

}  // namespace rp::test
