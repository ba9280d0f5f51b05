#pragma once
/// 8-bit sRGB encoding of linear colour channels for the 8-bit image formats (PNG, JPEG, ...):
/// the bytes the straightforward way gives (clamp to [0, 1], the sRGB curve with powf, then
/// OpenImageIO's float-to-uint8 conversion), read from a table instead of computing a power
/// per channel. The curve followed by the rounding to 8 bits is a non-decreasing step
/// function of the channel, so it is fixed by its 255 steps: each is found once, by bisection
/// over the floats with the straightforward path itself. A table indexed by a channel's top 16
/// bits holds each bucket's byte and the one step inside it, if any (the steps lie farther
/// apart than a bucket is wide everywhere in [0, 1]; checked when the table is made, with a
/// search over the steps where it would not hold).

#include <cstdint>
#include <span>

namespace rp {

/// The byte of one linear channel (NaN: whatever the straightforward path gives it).
uint8_t srgb8(float linear);

/// srgb8 of every channel: out[i] = srgb8(linear[i]); the spans have the same size.
void srgb8(std::span<const float> linear, std::span<uint8_t> out);

/// The straightforward path (srgb curve with powf, OpenImageIO's conversion) for one channel:
/// what the table must equal (tests).
uint8_t srgb8_direct(float linear);

}  // namespace rp
