/// tinygltf's implementation (Debian 12's libtinygltf-dev 2.7 ships the header), compiled
/// once here for raypack's glTF reader (io/loaders/gltf.cpp) and for the tests that write
/// glTF files with its writer. Configured for what raypack reads:
/// - no image decoding or encoding (TINYGLTF_NO_STB_IMAGE, _WRITE): the renderer has no
///   textures; a glTF image is accepted and ignored (gltf.cpp sets a loader that skips it),
///   and external image files are never opened (TINYGLTF_NO_EXTERNAL_IMAGE);
/// - no file system of its own (TINYGLTF_NO_FS): the reader's callbacks open every file by
///   raypack's input rule (io/input_file.h) and expand no path (tinygltf's own expands
///   `~` and variables through wordexp).
/// Debian's libtinygltf.so is built with stb_image, which raypack does not need, so it is not
/// linked. The library's warnings are its own: this file is built without raypack's.

// The writer (used by the tests) opens its files with std::ofstream even without a file system
// of its own; the header includes <fstream> only when it has one.
#include <fstream>

#define TINYGLTF_IMPLEMENTATION
#include "io/loaders/tinygltf_config.h"
