#pragma once
// The backend variants a test runs on: one method of every variant of every available backend.

#include <vector>

#include "backends/registry.h"

namespace rp::test {

/// Every variant of every available backend (Embree's "dynamic" among them), each once.
inline std::vector<TraceMethod> backend_variants() {
  std::vector<TraceMethod> out;
  for (const TraceMethod& m : list_methods()) {
    bool seen = false;
    for (const TraceMethod& o : out) seen |= o.backend == m.backend && o.variant == m.variant;
    if (!seen) out.push_back(m);
  }
  return out;
}

}  // namespace rp::test
