#pragma once
/// rp::Error, the exception raypack's calls throw: the part of base/error.h that is public
/// API. base/error.h adds the message builder and the checking macros, which stay inside
/// raypack: an installed header defines none of them (the debug-only check would follow the
/// consumer's NDEBUG, not the library's, and the names would collide with the consumer's).

#include <stdexcept>
#include <string>

namespace rp {

/// A failure the user can act on; what() is one line naming the file, flag or value.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace rp
