#pragma once
// Whether this build (and so the raypack it tests) is instrumented with AddressSanitizer:
// GCC's macro or clang's feature test.

namespace rp::test {

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kSanitized = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif
#else
inline constexpr bool kSanitized = false;
#endif

}  // namespace rp::test
