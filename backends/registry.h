#pragma once
/// The one place that names every backend. Callers pick a backend by name at run time.

#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "engine/backend.h"
#include "engine/scene.h"

namespace rp {

/// A backend the registry knows, and whether this machine can run it.
struct BackendEntry {
  std::string name;
  std::string description;
  std::vector<std::string> variants;  ///< accepted BackendOptions::variant values
  std::vector<std::string> coherent_methods;  ///< accepted BackendOptions::coherent_method values, default first
  std::vector<std::string> incoherent_methods;  ///< accepted BackendOptions::incoherent_method values, default first
  std::vector<std::pair<std::string, std::string>> facts;  ///< version, ISA, ... (for benchmark records)
  bool available = true;
  std::string unavailable_reason;  ///< why not, when !available
};

/// Every backend raypack has, available or not.
std::vector<BackendEntry> list_backends();

/// Names of the backends available on this machine.
std::vector<std::string> available_backends();

/// The backend used when none is asked for.
inline constexpr std::string_view kDefaultBackend = "embree";

/// Why backend `name` with `variant` cannot be built on this machine, when it cannot: the
/// message (listing the valid names, or saying why the backend is unavailable) and whether the
/// variant, rather than the backend, is at fault.
struct MethodProblem {
  bool variant = false;
  std::string message;
};
std::optional<MethodProblem> check_method(std::string_view name, std::string_view variant);

/// Builds `name` over `scene`. Throws rp::Error with check_method's message for an unknown or
/// unavailable backend or an unknown variant.
std::unique_ptr<Backend> make_backend(std::string_view name, const Scene& scene, const BackendOptions& options = {});

}  // namespace rp
