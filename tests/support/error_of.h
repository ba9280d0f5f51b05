#pragma once
// The message a setup call fails with, for tests that check the exact one-line errors.

#include <functional>
#include <string>

#include "base/error.h"

namespace rp::test {

/// The text used when f throws no rp::Error.
inline constexpr const char* kNoError = "no error";

/// what() of the rp::Error that f throws, or kNoError.
inline std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return kNoError;
}

}  // namespace rp::test
