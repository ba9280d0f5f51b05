#pragma once
// Out-of-memory messages that say what was being built and how many bytes were asked for.
// The raypack executable replaces the global operator new (out_of_memory.cpp) so that a
// failing allocation records its size before std::bad_alloc is thrown.

#include <cstddef>
#include <new>
#include <string>

#include "base/error.h"

namespace rp::cli {

/// Bytes of the most recent allocation that failed (0 when none has).
size_t failed_allocation_bytes();

/// Runs f(); a std::bad_alloc becomes rp::Error "out of memory while <what>: an allocation
/// of N bytes failed".
template <typename F>
auto with_memory_context(const std::string& what, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const std::bad_alloc&) {
    throw Error(cat("out of memory while ", what, ": an allocation of ", failed_allocation_bytes(), " bytes failed"));
  }
}

}  // namespace rp::cli
