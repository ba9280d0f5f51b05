#pragma once
/// Checks and messages shared by every reader of JSON text (scene files, bench results),
/// independent of the JSON library.

#include <cstddef>
#include <string>
#include <string_view>

namespace rp {

/// The deepest nesting of arrays and objects a JSON input may have. Scene and bench files
/// need 6 levels; the bound keeps every recursive walk of a parsed document (printing a value
/// in a message, say) far from the stack's end.
inline constexpr size_t kMaxJsonDepth = 64;

/// Throws rp::Error "<path>: line L, column C: nesting deeper than 64 levels" when `text`
/// opens more than kMaxJsonDepth arrays and objects at once (brackets inside strings do not
/// count). Linear, iterative; any bytes are accepted (syntax is the parser's job).
void check_json_depth(const std::string& path, std::string_view text);

/// 1-based line and column (in bytes) of the byte at 1-based offset `byte` (byte = size + 1
/// is the end of the text).
struct TextPosition {
  size_t line, column;
};
TextPosition position_of(std::string_view text, size_t byte);

/// A JSON library's exception message without its "[json.exception.<kind>.<id>] " and
/// "parse error at ...: " prefixes.
std::string json_reason(const std::string& what);

}  // namespace rp
