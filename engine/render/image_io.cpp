#include "engine/render/image_io.h"

#include <OpenImageIO/imageio.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>

#include "engine/error.h"
#include "engine/input_file.h"
#include "engine/output_file.h"
#include "engine/render/srgb8.h"

namespace rp {

namespace {

/// Lower-case extension of `path` (".png"), or empty.
std::string extension_of(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

/// Writes `spec` and `pixels` (of `format`, `stride` bytes per pixel or AutoStride) with the
/// OIIO writer for the extension of `path`, by rp::OutputFile.
void write_with_oiio(const std::string& path, const OIIO::ImageSpec& spec, OIIO::TypeDesc format,
                     const void* pixels, OIIO::stride_t stride = OIIO::AutoStride) {
  OutputFile file(path);
  auto out = OIIO::ImageOutput::create(file.temp_path());
  RP_CHECK(out, "cannot write '", path, "': no image writer for extension '", extension_of(path), "'");
  if (!(out->open(file.temp_path(), spec) && out->write_image(format, pixels, stride) && out->close())) {
    const std::string err = out->geterror();
    throw Error(cat("cannot write '", path, "': ", err.empty() ? "write failed" : err));
  }
  file.commit();
}

}  // namespace

void write_image(const std::string& path, const Image& image) {
  RP_CHECK(image.width > 0 && image.height > 0 &&
               image.rgb.size() == size_t(image.width) * size_t(image.height) * 3,
           "write_image: image for '", path, "' has no pixels");
  const std::string ext = extension_of(path);
  RP_CHECK(!ext.empty(), "cannot write '", path, "': no file extension to choose the format (.png, .exr, ...)");
  const bool is_float = ext == ".exr" || ext == ".hdr" || ext == ".pfm" || ext == ".tif" || ext == ".tiff";
  OIIO::ImageSpec spec(image.width, image.height, 3, is_float ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8);
  // Same pixels, same bytes: no write time in the header (OIIO stamps EXR files otherwise).
  spec.attribute("DateTime", "");
  if (is_float) {
    write_with_oiio(path, spec, OIIO::TypeDesc::FLOAT, image.rgb.data());
    return;
  }
  spec.attribute("oiio:ColorSpace", "sRGB");
  std::vector<uint8_t> bytes(image.rgb.size());  // the bytes OIIO made of sRGB floats, from a table (srgb8.h)
  srgb8(image.rgb, bytes);
  write_with_oiio(path, spec, OIIO::TypeDesc::UINT8, bytes.data());
}

void write_aovs(const std::string& path, const Aovs& a) {
  RP_CHECK(extension_of(path) == ".exr", "cannot write AOVs to '", path, "': AOVs are written as OpenEXR (.exr)");
  const size_t n = size_t(a.width) * size_t(a.height);
  RP_CHECK(n > 0 && a.depth.size() == n, "write_aovs: no pixels for '", path, "'");
  constexpr int kChannels = 11;
  OIIO::ImageSpec spec(a.width, a.height, kChannels, OIIO::TypeDesc::FLOAT);
  spec.channelnames = {"Z", "Ng.X", "Ng.Y", "Ng.Z", "N.X", "N.Y", "N.Z", "u", "v", "primId", "instanceId"};
  spec.channelformats.assign(kChannels, OIIO::TypeDesc::FLOAT);
  spec.channelformats[9] = spec.channelformats[10] = OIIO::TypeDesc::UINT;
  spec.z_channel = 0;
  spec.attribute("DateTime", "");
  // Interleaved pixels: 9 floats then two uint32, 44 bytes each.
  constexpr size_t kPixel = 44;
  std::vector<unsigned char> pixels(n * kPixel);
  for (size_t p = 0; p < n; ++p) {
    float f[9] = {a.depth[p], a.normal[3 * p], a.normal[3 * p + 1], a.normal[3 * p + 2], a.shading_normal[3 * p],
                  a.shading_normal[3 * p + 1], a.shading_normal[3 * p + 2], a.uv[2 * p], a.uv[2 * p + 1]};
    std::memcpy(&pixels[p * kPixel], f, sizeof f);
    std::memcpy(&pixels[p * kPixel + 36], &a.prim_id[p], 4);
    std::memcpy(&pixels[p * kPixel + 40], &a.instance_id[p], 4);
  }
  write_with_oiio(path, spec, OIIO::TypeDesc::UNKNOWN, pixels.data(), kPixel);
}

Image read_image(const std::string& path) {
  // The input rule (engine/input_file.h) before OIIO opens the file: a FIFO would block its
  // open and /dev/zero (or a link to it named .png) would feed it forever.
  uint64_t size = 0;
  ::close(open_regular_file(path, size));
  auto in = OIIO::ImageInput::open(path);
  RP_CHECK(in, "cannot read '", path, "': ", OIIO::geterror());
  const OIIO::ImageSpec& spec = in->spec();
  RP_CHECK(spec.width > 0 && spec.height > 0 && spec.nchannels > 0, "cannot read '", path, "': empty image");
  std::vector<float> all(size_t(spec.width) * spec.height * spec.nchannels);
  RP_CHECK(in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, all.data()), "cannot read '", path,
           "': ", in->geterror());
  Image img;
  img.width = spec.width;
  img.height = spec.height;
  img.rgb.resize(size_t(spec.width) * spec.height * 3);
  for (size_t p = 0; p < size_t(spec.width) * spec.height; ++p)
    for (int c = 0; c < 3; ++c) img.rgb[p * 3 + c] = all[p * spec.nchannels + std::min(c, spec.nchannels - 1)];
  return img;
}

}  // namespace rp
