// The 8-bit sRGB table (render/srgb8.h) against the straightforward path it replaces:
// the sRGB curve with powf, then OpenImageIO's float-to-uint8 conversion.

#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <vector>

#include "render/image_io.h"
#include "render/srgb8.h"
#include "tests/support/temp_dir.h"

namespace rp {
namespace {

/// Around every step of the byte (found here by bisection over the floats with the direct
/// path), at the first and last float of every 16-bit bucket of [0, 1], on a million random
/// channels (uniform in value and in bit pattern), and on the special values: the same byte.
TEST(Srgb8, TableEqualsTheDirectPath) {
  std::vector<float> probes = {0.0f, -0.0f, -1.0f, 1.0f, 2.0f, 1e30f, std::numeric_limits<float>::infinity(),
                               -std::numeric_limits<float>::infinity(), std::numeric_limits<float>::quiet_NaN(),
                               -std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::denorm_min(),
                               std::numeric_limits<float>::min(), 0.0031308f, std::nextafter(1.0f, 0.0f)};
  int steps = 0;
  for (int k = 1; k < 256; ++k) {
    uint32_t lo = 0, hi = 0x3F800000u;
    if (srgb8_direct(1.0f) < k) break;
    while (hi - lo > 1) {
      const uint32_t mid = lo + (hi - lo) / 2;
      (srgb8_direct(std::bit_cast<float>(mid)) >= k ? hi : lo) = mid;
    }
    ++steps;
    for (int d = -3; d <= 3; ++d) probes.push_back(std::bit_cast<float>(uint32_t(int64_t(hi) + d)));
  }
  EXPECT_EQ(steps, 255) << "every byte value is reached in [0, 1]";
  for (uint32_t b = 0; b <= 0x3F7Fu; ++b) {
    probes.push_back(std::bit_cast<float>(b << 16));
    probes.push_back(std::bit_cast<float>(b << 16 | 0xFFFFu));
  }
  std::mt19937 rng(8);
  std::uniform_real_distribution<float> unit(-0.25f, 1.25f);
  for (int i = 0; i < 500000; ++i) {
    probes.push_back(unit(rng));
    probes.push_back(std::bit_cast<float>(uint32_t(rng() % 0x3F800001u)));
  }
  size_t wrong = 0;
  for (const float c : probes)
    if (srgb8(c) != srgb8_direct(c) && ++wrong <= 5)
      ADD_FAILURE() << "channel " << c << " (bits " << std::hex << std::bit_cast<uint32_t>(c) << std::dec
                    << "): table " << int(srgb8(c)) << ", direct " << int(srgb8_direct(c));
  EXPECT_EQ(wrong, 0u) << "of " << probes.size() << " channels";
  // The span form is the scalar one channel by channel.
  std::vector<uint8_t> out(probes.size());
  srgb8(probes, out);
  for (size_t i = 0; i < probes.size(); ++i) ASSERT_EQ(out[i], srgb8(probes[i])) << i;
}

/// A PNG written by write_image is the file OpenImageIO writes from the sRGB floats as before
/// the table (the curve with powf, the float buffer converted by the writer), byte for byte,
/// with an odd width (rows that end off the converter's vector path), NaN, negative and
/// over-range channels.
TEST(Srgb8, PngBytesEqualTheFloatPath) {
  const rp::test::TempDir tmp;
  const std::filesystem::path& dir = tmp.dir;
  Image img;
  img.width = 37;
  img.height = 23;
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> unit(-0.1f, 1.1f);
  for (int i = 0; i < img.width * img.height * 3; ++i)
    img.rgb.push_back(i % 97 == 0 ? std::numeric_limits<float>::quiet_NaN() : unit(rng));
  const std::string table_png = (dir / "table.png").string(), float_png = (dir / "float.png").string();
  write_image(table_png, img);
  std::vector<float> curve = img.rgb;
  for (float& c : curve) {
    c = std::clamp(c, 0.0f, 1.0f);
    c = c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
  }
  OIIO::ImageSpec spec(img.width, img.height, 3, OIIO::TypeDesc::UINT8);
  spec.attribute("DateTime", "");
  spec.attribute("oiio:ColorSpace", "sRGB");
  auto out = OIIO::ImageOutput::create(float_png);
  ASSERT_TRUE(out && out->open(float_png, spec) && out->write_image(OIIO::TypeDesc::FLOAT, curve.data()) && out->close());
  const auto bytes = [](const std::string& p) {
    std::ifstream f(p, std::ios::binary);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
  };
  EXPECT_EQ(bytes(table_png), bytes(float_png));
  EXPECT_GT(bytes(table_png).size(), 100u);
}

}  // namespace
}  // namespace rp
