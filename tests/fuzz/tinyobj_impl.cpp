/// tinyobjloader's implementation, compiled into the fuzz targets that read OBJ files
/// (fuzz_obj, fuzz_json) only, with the fuzz build's sanitizers and coverage: Debian's
/// libtinyobjloader.so is not instrumented, so without this libFuzzer would not see the OBJ
/// and MTL parsers' branches and AddressSanitizer would not check their memory accesses. The
/// definitions here are the same code as the library's (same header, same configuration:
/// float, no earcut) and, being in the executable, take precedence over the shared library's.

#define TINYOBJLOADER_IMPLEMENTATION
#include <tiny_obj_loader.h>
