#include "render/srgb8.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <vector>

#include "base/error.h"

namespace rp {

namespace {

float srgb_curve(float c) {
  c = std::clamp(c, 0.0f, 1.0f);
  return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

/// Channels at or above 1.0f (bits 0x3F800000) all give the byte of 1; below, a bucket is the
/// floats sharing their top 16 bits.
constexpr uint32_t kOne = 0x3F800000u, kBuckets = (kOne >> 16) + 1;

struct Table {
  std::array<float, 256> step{};  ///< step[k]: the least channel whose byte is at least k (k = 1..255)
  std::vector<uint8_t> base;      ///< per bucket: the byte of its first float
  std::vector<float> next;        ///< per bucket: the one step inside it (+inf: none)
  bool one_step_per_bucket = true;
  uint8_t nan = 0, one = 0;

  Table() : base(kBuckets), next(kBuckets, std::numeric_limits<float>::infinity()) {
    nan = srgb8_direct(std::numeric_limits<float>::quiet_NaN());
    one = srgb8_direct(1.0f);
    // Bisection over the bit patterns of [0, 1] (ordered as the floats): the least c with a
    // byte of at least k.
    for (int k = 1; k < 256; ++k) {
      uint32_t lo = 0, hi = kOne;  // byte(lo) may be < k; byte(hi) >= k unless one < k
      if (one < k) {
        step[size_t(k)] = std::numeric_limits<float>::infinity();
        continue;
      }
      if (srgb8_direct(0.0f) >= k) {
        step[size_t(k)] = 0.0f;
        continue;
      }
      while (hi - lo > 1) {
        const uint32_t mid = lo + (hi - lo) / 2;
        (srgb8_direct(std::bit_cast<float>(mid)) >= k ? hi : lo) = mid;
      }
      step[size_t(k)] = std::bit_cast<float>(hi);
    }
    for (uint32_t b = 0; b < kBuckets; ++b) {
      const float first = std::bit_cast<float>(b << 16);
      base[b] = by_steps(first);
      int inside = 0;
      for (int k = base[b] + 1; k < 256 && (std::bit_cast<uint32_t>(step[size_t(k)]) >> 16) == b; ++k)
        if (step[size_t(k)] > first) {
          if (++inside == 1) next[b] = step[size_t(k)];
        }
      one_step_per_bucket = one_step_per_bucket && inside <= 1;
    }
  }

  /// The byte of c in [0, 1) by a search over the steps.
  uint8_t by_steps(float c) const {
    int k = 0;
    for (int half = 128; half > 0; half /= 2)
      if (k + half < 256 && step[size_t(k + half)] <= c) k += half;
    return uint8_t(k);
  }
};

const Table& table() {
  static const Table t;
  return t;
}

}  // namespace

uint8_t srgb8_direct(float linear) {
  // OpenImageIO's conversion as image writers use it, on a run long enough for its vector
  // path (the same value in every slot).
  std::array<float, 16> in;
  in.fill(srgb_curve(linear));
  std::array<uint8_t, 16> out{};
  const bool ok = OIIO::convert_pixel_values(OIIO::TypeDesc::FLOAT, in.data(), OIIO::TypeDesc::UINT8, out.data(), 16);
  RP_CHECK(ok, "srgb8: OpenImageIO cannot convert float to uint8");
  return out[0];
}

namespace {

uint8_t encode(const Table& t, float linear) {
  const uint32_t bits = std::bit_cast<uint32_t>(linear);
  if (linear != linear) return t.nan;
  if (bits >> 31) return t.base[0];  // negative (and -0): clamped to 0
  if (bits >= kOne) return t.one;    // 1 and above, +inf
  if (!t.one_step_per_bucket) return t.by_steps(linear);
  const uint32_t b = bits >> 16;
  return uint8_t(t.base[b] + (linear >= t.next[b]));
}

}  // namespace

uint8_t srgb8(float linear) { return encode(table(), linear); }

void srgb8(std::span<const float> linear, std::span<uint8_t> out) {
  RP_CHECK(linear.size() == out.size(), "srgb8: ", linear.size(), " channels into ", out.size(), " bytes");
  const Table& t = table();
  for (size_t i = 0; i < linear.size(); ++i) out[i] = encode(t, linear[i]);
}

}  // namespace rp
