#include "backends/registry.h"

#include <algorithm>

#include "backends/embree/embree_backend.h"
#include "backends/simd/simd_backend.h"
#include "base/error.h"

namespace rp {

namespace {

/// The simd backend's kernels are compiled for AVX2+FMA; this file is not, so the check
/// itself runs on any x86-64 CPU.
bool cpu_has_avx2_fma() {
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
}

/// The scene a SceneSharingBackend owns: a base declared before the backend's, so that the
/// scene is made first and destroyed last.
struct SceneOwner {
  std::shared_ptr<const Scene> scene;
};

/// A backend that shares ownership of the scene it was built over; every call goes to the
/// backend built over that scene.
class SceneSharingBackend final : private SceneOwner, public ForwardingBackend {
 public:
  SceneSharingBackend(std::shared_ptr<const Scene> scene, std::unique_ptr<Backend> backend)
      : SceneOwner{std::move(scene)}, ForwardingBackend(*SceneOwner::scene, std::move(backend)) {}
};

}  // namespace

std::vector<BackendEntry> list_backends() {
  const bool simd_ok = cpu_has_avx2_fma();
  const embree::DeviceFacts e = embree::device_facts();
  const auto yes = [](bool b) { return std::string(b ? "yes" : "no"); };
  return {{"embree", "Intel Embree 3 (production backend; user geometry for analytic primitives)",
           embree::variants(), embree::coherent_methods(), embree::incoherent_methods(),
           {{"version", e.version}, {"isa", e.isa}, {"native_ray8", yes(e.native_ray8)},
            {"native_ray16", yes(e.native_ray16)}, {"ray_stream", yes(e.stream)}},
           true, ""},
          {"simd", "hand-written 8-wide BVH: large packets, 8-ray packets, ray streams and single rays, slab test, Moller-Trumbore (AVX2+FMA)",
           bvh8::variants(), bvh8::coherent_methods(), bvh8::incoherent_methods(), {{"isa", "avx2+fma"}},
           simd_ok, simd_ok ? "" : "this CPU lacks AVX2 or FMA, which the simd kernels are built for"}};
}

std::vector<std::string> available_backends() {
  std::vector<std::string> names;
  for (const BackendEntry& e : list_backends())
    if (e.available) names.push_back(e.name);
  return names;
}

BackendOptions TraceMethod::options() const {
  const bool coherent = coherence == Coherence::coherent;
  return {.variant = variant,
          .device_config = {},
          .coherent_method = coherent ? method : "",
          .incoherent_method = coherent ? "" : method};
}

std::vector<TraceMethod> list_methods() {
  std::vector<TraceMethod> out;
  for (const BackendEntry& e : list_backends()) {
    if (!e.available) continue;
    for (const std::string& v : e.variants) {
      for (const std::string& m : e.coherent_methods)
        out.push_back({cat(e.name, "/", v, ":", m), e.name, v, m, Coherence::coherent});
      for (const std::string& m : e.incoherent_methods) {
        const bool both = std::ranges::count(e.coherent_methods, m) > 0;
        out.push_back({cat(e.name, "/", v, ":", m, both ? "-incoherent" : ""), e.name, v, m, Coherence::incoherent});
      }
    }
  }
  return out;
}

std::optional<MethodProblem> check_method(std::string_view name, std::string_view variant) {
  std::string known;
  for (const BackendEntry& e : list_backends()) {
    known += (known.empty() ? "" : ", ") + e.name;
    if (e.name != name) continue;
    if (!e.available) return MethodProblem{false, cat("backend '", name, "' is not available on this machine: ", e.unavailable_reason)};
    std::string variants;
    for (const std::string& v : e.variants) {
      if (v == variant) return std::nullopt;
      variants += (variants.empty() ? "" : ", ") + v;
    }
    return MethodProblem{true, cat("'", variant, "' is not a variant of ", name, " (", variants, ")")};
  }
  return MethodProblem{false, cat("unknown backend '", name, "' (available: ", known, ")")};
}

std::unique_ptr<Backend> make_backend(std::string_view name, const Scene& scene, const BackendOptions& options) {
  if (const std::optional<MethodProblem> p = check_method(name, options.variant)) throw Error(p->message);
  if (name == "embree") return embree::make_backend(scene, options);
  return bvh8::make_backend(scene, options);
}

std::unique_ptr<Backend> make_backend(std::string_view name, std::shared_ptr<const Scene> scene,
                                      const BackendOptions& options) {
  RP_CHECK(scene != nullptr, "make_backend: no scene (a null shared_ptr)");
  std::unique_ptr<Backend> backend = make_backend(name, *scene, options);
  return std::make_unique<SceneSharingBackend>(std::move(scene), std::move(backend));
}

}  // namespace rp
