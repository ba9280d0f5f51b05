#pragma once
/// Text that goes into messages: values quoted from files, and whole lines for the terminal.

#include <string>
#include <string_view>
#include <vector>

namespace rp {

/// Text from a file safe to quote in a one-line message: bytes other than printable ASCII
/// become '?', text longer than 32 characters is cut and marked with "...".
std::string printable(std::string_view s);

/// A message as one terminal line: valid UTF-8 is kept, and every control character (a
/// newline, an escape sequence) and every byte of invalid UTF-8 becomes '?'.
std::string one_line(std::string_view s);

/// The fields of `line` between runs of characters for which `separator` is true (no empty
/// fields), into `out` (cleared first).
void split_fields(std::string_view line, bool (*separator)(char), std::vector<std::string_view>& out);

/// Prints "raypack: warning: <one_line(message)>" and a newline on standard error, unless
/// warnings are off.
void warn(std::string_view message);

/// Turns warn() on (the default) or off for the whole process: the MPI ranks other than rank
/// 0 turn it off, since rank 0 prints the same warnings.
void set_warnings(bool on);

}  // namespace rp
