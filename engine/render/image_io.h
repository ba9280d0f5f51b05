#pragma once
/// Image files through OpenImageIO. image_io.cpp is the only engine file that includes OIIO
/// (OIIO 2.4 bundles its own fmt headers).

#include <string>

#include "engine/render/render.h"

namespace rp {

/// Writes linear RGB `image` to `path`; the format follows the extension. 8-bit formats
/// (PNG, JPEG, ...) get the sRGB transfer curve and are clamped to [0, 1]; float formats
/// (EXR, HDR) are written linear. Written by rp::OutputFile (engine/output_file.h), so
/// `path` is never left half-written. Throws rp::Error naming the path.
void write_image(const std::string& path, const Image& image);

/// Writes `aovs` as one multi-channel OpenEXR file (the extension must be .exr): channels
/// Z (depth), Ng.X/Y/Z (geometric normal), N.X/Y/Z (shading normal), u, v (float) and
/// primId (uint32, 0xffffffff where the ray missed). Written by rp::OutputFile.
void write_aovs(const std::string& path, const Aovs& aovs);

/// Reads an image as linear-as-stored float RGB (the first three channels; grey is
/// replicated). Throws rp::Error naming the path.
Image read_image(const std::string& path);

}  // namespace rp
