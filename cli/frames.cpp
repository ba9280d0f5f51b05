#include "cli/frames.h"

#include <algorithm>
#include <regex>

#include "cli/args.h"

namespace rp::cli {

namespace {

/// Where the file name of `path` starts.
size_t name_start(const std::string& path) {
  const size_t slash = path.rfind('/');
  return slash == std::string::npos ? 0 : slash + 1;
}

/// The runs of '#' in the file name of `path`: how many, and where the last one is.
struct Runs {
  size_t count = 0, at = 0, length = 0;
};

Runs runs_of(const std::string& path) {
  Runs r;
  for (size_t i = name_start(path); (i = path.find('#', i)) != std::string::npos;) {
    const size_t end = std::min(path.find_first_not_of('#', i), path.size());
    ++r.count;
    r.at = i;
    r.length = end - i;
    i = end;
  }
  return r;
}

}  // namespace

FrameRange parse_frames(const std::string& text) {
  static const std::regex re(R"(^\s*(\d{1,9})\s*:\s*(\d{1,9})\s*$)");
  std::smatch m;
  if (std::regex_match(text, m, re)) {
    const FrameRange r{std::stoll(m[1]), std::stoll(m[2])};
    if (r.first <= r.last) return r;
  }
  throw UsageError(cat("--frames: '", text, "' is not FIRST:LAST (frame numbers, 0 <= FIRST <= LAST)"));
}

std::string frame_path(const std::string& pattern, int64_t frame) {
  const Runs r = runs_of(pattern);
  if (r.count == 0) return pattern;
  std::string number = std::to_string(frame);
  if (number.size() < r.length) number.insert(0, r.length - number.size(), '0');
  return pattern.substr(0, r.at) + number + pattern.substr(r.at + r.length);
}

void check_frame_pattern(const std::string& flag, const std::string& pattern, const FrameRange& frames) {
  const Runs r = runs_of(pattern);
  if (r.count > 1)
    throw UsageError(cat(flag, ": '", pattern, "' has ", r.count, " runs of '#'; one stands for the frame number"));
  if (r.count == 0 && frames.count() > 1)
    throw UsageError(cat(flag, ": '", pattern, "' has no run of '#' to number ", frames.count(),
                         " frames by (e.g. frame-####.png)"));
}

}  // namespace rp::cli
