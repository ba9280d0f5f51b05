#pragma once
/// tinygltf as raypack configures it (see io/loaders/tinygltf_impl.cpp): include this,
/// never <tiny_gltf.h> directly, so every translation unit sees the same declarations.

#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#define TINYGLTF_NO_FS
#include <tiny_gltf.h>
