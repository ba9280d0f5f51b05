#include "render/image_io.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <memory>

#include "base/error.h"
#include "base/text.h"
#include "io/input_file.h"
#include "io/output_file.h"
#include "render/srgb8.h"

namespace rp {

namespace {

/// Lower-case extension of `path` (".png"), or empty.
std::string extension_of(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

/// OIIO's writers through a descriptor: every write is checked here, whether or not the
/// writer looks at what write() returns (libpng's callback does not), and the first failure
/// is kept for write_with_oiio to report. Reads and seeks are there for writers that patch
/// their headers (OpenEXR's offset table, TIFF's directory).
class DescriptorProxy final : public OIIO::Filesystem::IOProxy {
 public:
  explicit DescriptorProxy(int fd) : IOProxy("", Write), fd_(fd) {}
  const char* proxytype() const override { return "raypack-descriptor"; }
  size_t write(const void* buf, size_t size) override {
    const size_t n = pwrite(buf, size, m_pos);
    m_pos += int64_t(n);
    return n;
  }
  size_t pwrite(const void* buf, size_t size, int64_t offset) override {
    const int e = pwrite_all(fd_, buf, size, uint64_t(offset));
    if (e != 0 && failure_ == 0) failure_ = e;
    return e == 0 ? size : 0;
  }
  size_t read(void* buf, size_t size) override {
    const size_t n = pread(buf, size, m_pos);
    m_pos += int64_t(n);
    return n;
  }
  size_t pread(void* buf, size_t size, int64_t offset) override {
    char* p = static_cast<char*>(buf);
    size_t done = 0;
    while (done < size) {
      const ssize_t r = ::pread(fd_, p + done, size - done, offset + int64_t(done));
      if (r < 0 && errno == EINTR) continue;
      if (r <= 0) break;
      done += size_t(r);
    }
    return done;
  }
  size_t size() const override {
    struct stat st {};
    return ::fstat(fd_, &st) == 0 ? size_t(st.st_size) : 0;
  }
  /// The errno of the first write that failed, or 0.
  int failure() const { return failure_; }

 private:
  int fd_;
  int failure_ = 0;
};

/// The OIIO writer for the extension of `path`, or rp::Error naming the path: none for the
/// extension, or one that cannot write through a descriptor (so its writes go unchecked).
std::unique_ptr<OIIO::ImageOutput> image_writer(const std::string& path) {
  const std::string ext = extension_of(path);
  RP_CHECK(!ext.empty(), "cannot write '", path, "': no file extension to choose the format (.png, .exr, ...)");
  auto out = OIIO::ImageOutput::create(path);
  RP_CHECK(out, "cannot write '", path, "': no image writer for extension '", ext, "'");
  RP_CHECK(out->supports("ioproxy"), "cannot write '", path, "': the ", out->format_name(),
           " writer cannot report a failed write (a full disk); use .png, .exr, .tif, .jpg, .hdr, ...");
  return out;
}

/// Writes `spec` and `pixels` (of `format`, `stride` bytes per pixel or AutoStride) with the
/// OIIO writer for the extension of `path`, through rp::OutputFile.
void write_with_oiio(const std::string& path, const OIIO::ImageSpec& spec, OIIO::TypeDesc format,
                     const void* pixels, OIIO::stride_t stride = OIIO::AutoStride) {
  auto writer = image_writer(path);
  OutputFile file(path);
  DescriptorProxy proxy(file.fd());
  // Declared after the proxy, so destroyed before it: a writer whose close failed closes again
  // in its destructor (OpenEXR's does), writing through the proxy.
  const std::unique_ptr<OIIO::ImageOutput> out = std::move(writer);
  const bool ok = out->set_ioproxy(&proxy) && out->open(file.temp_path(), spec) &&
                  out->write_image(format, pixels, stride) && out->close();
  if (proxy.failure() != 0) file.fail(std::strerror(proxy.failure()));
  if (!ok) {
    const std::string err = out->geterror();
    throw Error(cat("cannot write '", path, "': ", err.empty() ? "write failed" : one_line(err)));
  }
  file.commit();
}

}  // namespace

void check_image_output(const std::string& path) {
  image_writer(path);
  check_output(path);
}

void check_aov_output(const std::string& path) {
  RP_CHECK(extension_of(path) == ".exr", "cannot write AOVs to '", path, "': AOVs are written as OpenEXR (.exr)");
  check_image_output(path);
}

void write_image(const std::string& path, const Image& image) {
  RP_CHECK(image.width > 0 && image.height > 0 &&
               image.rgb.size() == size_t(image.width) * size_t(image.height) * 3,
           "write_image: image for '", path, "' has no pixels");
  const std::string ext = extension_of(path);
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
  // The input rule (io/input_file.h) before OIIO opens the file: a FIFO would block its
  // open and /dev/zero (or a link to it named .png) would feed it forever.
  uint64_t size = 0;
  ::close(open_regular_file(path, size));
  auto in = OIIO::ImageInput::open(path);
  RP_CHECK(in, "cannot read '", path, "': ", one_line(OIIO::geterror()));
  const OIIO::ImageSpec& spec = in->spec();
  RP_CHECK(spec.nchannels > 0, "cannot read '", path, "': an image without channels");
  // The size the header claims is checked before memory is asked for: a few bytes of PNG can
  // claim 50000x50000 pixels.
  check_image_size(cat("cannot read '", path, "': its size"), spec.width, spec.height);
  RP_CHECK(spec.depth <= 1 && spec.z == 0, "cannot read '", path, "': a volume image (depth ", spec.depth, ")");
  const int channels = spec.nchannels >= 3 ? 3 : 1;  // only what the image keeps is read
  const size_t n = size_t(spec.width) * size_t(spec.height);
  Image img;
  img.width = spec.width;
  img.height = spec.height;
  img.rgb.resize(n * 3);
  RP_CHECK(in->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, img.rgb.data(), 3 * sizeof(float)), "cannot read '",
           path, "': ", one_line(in->geterror()));
  if (channels == 1)  // grey (and grey-alpha): the grey channel into all three
    for (size_t p = 0; p < n; ++p) img.rgb[p * 3 + 1] = img.rgb[p * 3 + 2] = img.rgb[p * 3];
  return img;
}

}  // namespace rp
