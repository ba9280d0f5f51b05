#include "engine/image_io.h"

#include <OpenImageIO/imageio.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <system_error>
#include <unistd.h>

#include "engine/error.h"

namespace rp {

namespace {

float srgb_encode(float c) {
  c = std::clamp(c, 0.0f, 1.0f);
  return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

}  // namespace

void write_image(const std::string& path, const Image& image) {
  namespace fs = std::filesystem;
  RP_CHECK(image.width > 0 && image.height > 0 &&
               image.rgb.size() == size_t(image.width) * size_t(image.height) * 3,
           "write_image: image for '", path, "' has no pixels");
  const fs::path target(path);
  std::string ext = target.extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  RP_CHECK(!ext.empty(), "cannot write '", path, "': no file extension to choose the format (.png, .exr, ...)");
  // Temporary name keeps the extension so OIIO picks the same writer.
  const fs::path tmp = target.parent_path() / (".raypack-" + std::to_string(::getpid()) + "-" +
                                               target.filename().stem().string() + ext);
  auto out = OIIO::ImageOutput::create(tmp.string());
  RP_CHECK(out, "cannot write '", path, "': no image writer for extension '", ext, "'");
  const bool is_float = ext == ".exr" || ext == ".hdr" || ext == ".pfm" || ext == ".tif" || ext == ".tiff";
  OIIO::ImageSpec spec(image.width, image.height, 3, is_float ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8);
  // Same pixels, same bytes: no write time in the header (OIIO stamps EXR files otherwise).
  spec.attribute("DateTime", "");
  std::vector<float> pixels = image.rgb;
  if (!is_float) {
    spec.attribute("oiio:ColorSpace", "sRGB");
    for (float& c : pixels) c = srgb_encode(c);
  }
  bool ok = out->open(tmp.string(), spec) && out->write_image(OIIO::TypeDesc::FLOAT, pixels.data()) && out->close();
  if (!ok) {
    std::string err = out->geterror();
    std::error_code ec;
    fs::remove(tmp, ec);
    throw Error(cat("cannot write '", path, "': ", err.empty() ? "write failed" : err));
  }
  std::error_code ec;
  fs::rename(tmp, target, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw Error(cat("cannot write '", path, "': ", ec.message()));
  }
}

namespace {

/// Moves a finished temporary file onto `target`, or removes it and throws.
void commit_file(const std::filesystem::path& tmp, const std::string& target) {
  std::error_code ec;
  std::filesystem::rename(tmp, target, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    throw Error(cat("cannot write '", target, "': ", ec.message()));
  }
}

}  // namespace

void write_aovs(const std::string& path, const Aovs& a) {
  namespace fs = std::filesystem;
  const fs::path target(path);
  std::string ext = target.extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  RP_CHECK(ext == ".exr", "cannot write AOVs to '", path, "': AOVs are written as OpenEXR (.exr)");
  const size_t n = size_t(a.width) * size_t(a.height);
  RP_CHECK(n > 0 && a.depth.size() == n, "write_aovs: no pixels for '", path, "'");
  constexpr int kChannels = 10;
  OIIO::ImageSpec spec(a.width, a.height, kChannels, OIIO::TypeDesc::FLOAT);
  spec.channelnames = {"Z", "Ng.X", "Ng.Y", "Ng.Z", "N.X", "N.Y", "N.Z", "u", "v", "primId"};
  spec.channelformats.assign(kChannels, OIIO::TypeDesc::FLOAT);
  spec.channelformats[9] = OIIO::TypeDesc::UINT;
  spec.z_channel = 0;
  spec.attribute("DateTime", "");
  // Interleaved pixels: 9 floats then one uint32, 40 bytes each.
  std::vector<unsigned char> pixels(n * 40);
  for (size_t p = 0; p < n; ++p) {
    float f[9] = {a.depth[p], a.normal[3 * p], a.normal[3 * p + 1], a.normal[3 * p + 2], a.shading_normal[3 * p],
                  a.shading_normal[3 * p + 1], a.shading_normal[3 * p + 2], a.uv[2 * p], a.uv[2 * p + 1]};
    std::memcpy(&pixels[p * 40], f, sizeof f);
    std::memcpy(&pixels[p * 40 + 36], &a.prim_id[p], 4);
  }
  const fs::path tmp = target.parent_path() / (".raypack-" + std::to_string(::getpid()) + "-" + target.filename().string());
  auto out = OIIO::ImageOutput::create(tmp.string());
  RP_CHECK(out, "cannot write '", path, "': no OpenEXR writer");
  const bool ok = out->open(tmp.string(), spec) &&
                  out->write_image(OIIO::TypeDesc::UNKNOWN, pixels.data(), 40) && out->close();
  if (!ok) {
    const std::string err = out->geterror();
    std::error_code ec;
    fs::remove(tmp, ec);
    throw Error(cat("cannot write '", path, "': ", err.empty() ? "write failed" : err));
  }
  commit_file(tmp, path);
}

Image read_image(const std::string& path) {
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
