#pragma once
/// Image files through OpenImageIO. image_io.cpp is the only engine file that includes OIIO
/// (OIIO 2.4 bundles its own fmt headers).

#include <string>

#include "render/render.h"

namespace rp {

/// Writes linear RGB `image` to `path`; the format follows the extension. 8-bit formats
/// (PNG, JPEG, ...) get the sRGB transfer curve and are clamped to [0, 1]; float formats
/// (EXR, HDR) are written linear. Written by rp::OutputFile (io/output_file.h), so
/// `path` is never left half-written: every write the image writer makes is checked (a full
/// disk fails the call and keeps the old file). Throws rp::Error naming the path.
void write_image(const std::string& path, const Image& image);

/// Checks, before any work, that write_image(path, ...) can write `path`: an extension with an
/// image writer that reports failed writes, and an output rp::OutputFile can make
/// (check_output). Throws the rp::Error write_image would.
void check_image_output(const std::string& path);

/// The same for write_aovs (the extension must be .exr).
void check_aov_output(const std::string& path);

/// Writes `aovs` as one multi-channel OpenEXR file (the extension must be .exr): channels
/// Z (depth), Ng.X/Y/Z (geometric normal), N.X/Y/Z (shading normal), u, v (float) and
/// primId (uint32, 0xffffffff where the ray missed). Written by rp::OutputFile.
void write_aovs(const std::string& path, const Aovs& aovs);

/// Reads an image as linear-as-stored float RGB (the first three channels; grey is
/// replicated). The input rule of io/input_file.h applies, and an image whose header
/// claims more than check_image_size allows is refused before its pixels are read. Throws
/// rp::Error naming the path.
Image read_image(const std::string& path);

}  // namespace rp
