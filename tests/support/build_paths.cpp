#include "tests/support/build_paths.h"

namespace rp::test {

const char* const kSourceDir = RP_SOURCE_DIR;
const char* const kSharedScenes = RP_SHARED_SCENES;
const char* const kRaypackExe = RP_RAYPACK_EXE;
const char* const kMpiexec = RP_MPIEXEC;

}  // namespace rp::test
