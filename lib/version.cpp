#include "raypack/version.h"

// The umbrella header compiled once inside the library: every public header must stand alone.
#include "raypack/raypack.h"

namespace rp {

const char* version() noexcept { return RAYPACK_VERSION_STRING; }

}  // namespace rp
