#include "backends/registry.h"

#include "backends/embree/embree_backend.h"
#include "engine/error.h"

namespace rp {

std::vector<BackendEntry> list_backends() {
  return {{"embree", "Intel Embree 3 (production backend; user geometry for analytic primitives)",
           embree::variants(), true, ""}};
}

std::vector<std::string> available_backends() {
  std::vector<std::string> names;
  for (const BackendEntry& e : list_backends())
    if (e.available) names.push_back(e.name);
  return names;
}

std::unique_ptr<Backend> make_backend(std::string_view name, const Scene& scene, const BackendOptions& options) {
  std::string known;
  for (const BackendEntry& e : list_backends()) {
    known += (known.empty() ? "" : ", ") + e.name;
    if (e.name != name) continue;
    RP_CHECK(e.available, "backend '", name, "' is not available on this machine: ", e.unavailable_reason);
    if (name == "embree") return embree::make_backend(scene, options);
  }
  throw Error(cat("unknown backend '", name, "' (available: ", known, ")"));
}

}  // namespace rp
