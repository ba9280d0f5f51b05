#pragma once
/// What a caller says about the rays of a batch that break the valid-ray rule (core/ray.h):
/// every backend reports them as misses and never as occluded, so tracing goes on, and the
/// caller warns once per batch with this one line (`raypack trace` on standard error, the
/// Python module as a RuntimeWarning or, when asked, an exception).

#include <cstddef>
#include <string>
#include <string_view>

#include "base/error.h"

namespace rp {

/// "<source>: <invalid> of <total> rays are outside the valid-ray rule (...) and were reported
/// as misses", the rule spelled out in the parentheses; `source` names the batch (a ray file,
/// or the call that traced it).
inline std::string invalid_rays_message(std::string_view source, size_t invalid, size_t total) {
  return cat(source, ": ", invalid, " of ", total,
             " rays are outside the valid-ray rule (finite, origin |x| <= 2^30, largest direction component in "
             "[2^-26, 2^31], 0 <= tnear <= tfar) and were reported as misses");
}

}  // namespace rp
