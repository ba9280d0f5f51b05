#pragma once
/// The version of the raypack library a program runs with.

namespace rp {

/// "MAJOR.MINOR.PATCH" of the libraypack.so loaded at run time (the project version it was
/// built from); compare with raypack_VERSION, the version find_package(raypack) found at
/// build time. A static string, never null.
const char* version() noexcept;

}  // namespace rp
