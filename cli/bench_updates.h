#pragma once
// `raypack bench`'s update figures: Backend::update() timed after each kind of motion the scene
// allows (every mesh deformed, every instance moved), against a full build of the same frame,
// and the trace speed of the updated backend against one built afresh over the moved scene.

#include <cstdio>
#include <nlohmann/json.hpp>
#include <span>

#include "backends/registry.h"
#include "cli/bench_timing.h"
#include "core/scene.h"

namespace rp::cli {

/// The update figures of `scene` for each backend variant among `chosen`, printed to `table`
/// (when not null) and returned as the scene's "updates" array: per motion, --build-runs
/// frames, each update followed by a build over the same frame (medians, and the median of
/// their per-frame ratio), then the updated and the built backend tracing `kinds` in
/// alternation (primary rays as coherent, diffuse rays as incoherent; the others are left out).
nlohmann::ordered_json bench_updates(const Scene& scene, std::span<const TraceMethod> chosen,
                                     std::span<const Kind> kinds, const BenchArgs& a, std::FILE* table);

}  // namespace rp::cli
