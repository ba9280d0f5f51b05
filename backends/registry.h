#pragma once
/// The one place that names every backend. Callers pick a backend by name at run time.

#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/backend.h"
#include "core/scene.h"

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

/// One way of tracing, named "backend/variant:method" everywhere a method is named (bench,
/// rp_bench, stability, charts): a backend variant and the method it traces with under one
/// coherence hint, e.g. "simd/watertight:large", "embree/default:packet16". A method listed
/// for both hints keeps its name when coherent and is "<method>-incoherent" otherwise
/// ("embree/default:stream", "embree/default:stream-incoherent").
struct TraceMethod {
  std::string name, backend, variant, method;
  Coherence coherence;
  /// The options that build `variant` tracing with `method` under `coherence`.
  BackendOptions options() const;
};

/// The methods of the available backends: each variant with each coherent method, then each
/// incoherent one, in the registry's order.
std::vector<TraceMethod> list_methods();

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
///
/// Ownership: the backend keeps a reference to `scene` (the triangles some kernels read, the
/// analytic primitives and planes every backend tests beside its structure): the caller owns
/// the scene, must keep it alive for as long as the backend lives, and destroys the backend
/// first. The scene may change meanwhile: Backend::update() then brings the backend up to
/// date, and it refuses to trace until then (core/backend.h). A temporary scene would die at the end of the call, so
/// passing one is a compile error (the deleted overload below); to hand the scene's lifetime to the backend, use the
/// shared_ptr overload.
std::unique_ptr<Backend> make_backend(std::string_view name, const Scene& scene, const BackendOptions& options = {});

/// Refused at compile time: the backend would keep a reference to a scene that is destroyed
/// at the end of the full expression (`make_backend("simd", load_scene(path))`).
std::unique_ptr<Backend> make_backend(std::string_view name, const Scene&& scene, const BackendOptions& options = {}) = delete;

/// Builds `name` over a scene the backend shares: the backend holds `scene` (which must not be
/// null) until it is destroyed, so the scene outlives it whoever else lets go of it. The scene
/// is const through this pointer; whoever changes it through another calls update() before
/// tracing again. Throws as the overload above, and rp::Error for a null scene.
std::unique_ptr<Backend> make_backend(std::string_view name, std::shared_ptr<const Scene> scene,
                                      const BackendOptions& options = {});

}  // namespace rp
