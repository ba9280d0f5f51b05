#pragma once
// `raypack render --frames`: the frame range and the output name of each frame.

#include <cstdint>
#include <string>

namespace rp::cli {

/// Frames FIRST..LAST of an animation, both included.
struct FrameRange {
  int64_t first = 0, last = 0;  ///< 0 <= first <= last < 10^9
  int64_t count() const { return last - first + 1; }
};

/// --frames's value "FIRST:LAST" (frame numbers, 0 <= FIRST <= LAST, at most 9 digits each),
/// or a usage error naming the flag.
FrameRange parse_frames(const std::string& text);

/// Output `pattern` for frame `frame`: the run of '#' in its file name (the part after the last
/// '/') replaced by the frame number, zero-padded to the run's length ("frame-####.png", 7:
/// "frame-0007.png"; a number wider than the run is written whole: 12345). A pattern without
/// '#' is returned as it is.
std::string frame_path(const std::string& pattern, int64_t frame);

/// Checks output `pattern` (given by `flag`, e.g. -o) for `frames`, before any work: a usage
/// error naming the flag when its file name has more than one run of '#' (which would the
/// number be?), or none while several frames are rendered (every frame would overwrite the
/// last).
void check_frame_pattern(const std::string& flag, const std::string& pattern, const FrameRange& frames);

}  // namespace rp::cli
