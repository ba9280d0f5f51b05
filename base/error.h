#pragma once
/// The project's error type (base/error_type.h, the public part) and checks, for raypack's
/// own code: no public header includes this one.
///
/// User and environment failures (bad flags, bad files, a failing library) throw rp::Error
/// with a one-line message at setup time. Query paths are noexcept; only main() turns an
/// Error into an exit status.

#include <sstream>
#include <string>
#include <utility>

#include "base/error_type.h"

namespace rp {

/// Builds a message from streamable parts: rp::cat("bad value ", x, " in ", file).
template <typename... Parts>
std::string cat(Parts&&... parts) {
  std::ostringstream s;
  (s << ... << std::forward<Parts>(parts));
  return s.str();
}

}  // namespace rp

/// Always-on check for setup code: throws rp::Error("<message>") when cond is false.
#define RP_CHECK(cond, ...)                                                          \
  do {                                                                               \
    if (!(cond)) throw ::rp::Error(::rp::cat(__VA_ARGS__));                          \
  } while (0)

/// Debug-only check, the only one allowed in hot loops.
#ifdef NDEBUG
#define RP_DCHECK(cond) ((void)0)
#else
#include <cassert>
#define RP_DCHECK(cond) assert(cond)
#endif
