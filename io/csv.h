#pragma once
/// The text side of raypack's record files (ray and hit files, io/rayfile.h; point files,
/// io/pointfile.h): one reader of CSV lines and one number format, so that every file reads
/// and writes by the same rules.
///
/// Reading: UTF-8/ASCII text, lines end in "\n" or "\r\n". Line 1 names the columns,
/// comma-separated, in any order (parse_header); it may start with a UTF-8 byte order mark
/// (spreadsheets) and with '#' (numpy.savetxt's `header=`), and names may have blanks around
/// them. Each following line holds one value per column, blanks around a value allowed, no
/// quotes. Blank lines are accepted only at the end of the file. Every failure throws
/// rp::Error "<path>: line N: <what>".
///
/// Writing: floats as printf's `%.9g` in the C locale (append_float), which reads back to the
/// same bits for every finite value, ±0 and ±inf; every NaN is written `nan`.

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "io/input_file.h"

namespace rp::csv {

/// The most columns a file kind has.
inline constexpr size_t kMaxColumns = 12;

/// The columns of a CSV file of one kind, in the order the writer writes them (line 1 of a
/// written file is these names joined by commas); the first `required` must be in every file,
/// the others default to `defaults` (text parsed like a value; null for required columns).
struct Columns {
  std::array<const char*, kMaxColumns> names;
  size_t count, required;
  std::array<const char*, kMaxColumns> defaults;
};

/// `text` without blanks (spaces, tabs) at either end.
std::string_view trim(std::string_view text);

/// The fields of one CSV line, blanks around each value dropped.
std::vector<std::string_view> split(std::string_view line);

/// Line 1 of a CSV file of `columns`: for each column of the file, the index in `columns` of
/// the column it holds. Returns an empty vector with `why` set when the line is no such
/// header ("no column 'oz' (columns: ...)").
std::vector<size_t> parse_header(std::string_view line, const Columns& columns, std::string& why);

/// Line 1 of a written file of `columns`: their names joined by commas, and "\n".
std::string head(const Columns& columns);

/// Where a CSV value came from, for messages.
struct Place {
  const std::string& path;
  uint64_t line;
};

/// A value std::from_chars accepts for float (decimal or exponent notation, optional leading
/// '-', `inf`, `nan`, case-insensitive; no '+', no hex) within the float32 range; else
/// rp::Error "<path>: line N: '<s>' is not a number" (or "is out of the float32 range").
float parse_float(const Place& at, std::string_view s);

/// Appends `x` as printf("%.9g") in the C locale, whatever the global locale; every NaN as
/// "nan".
void append_float(std::string& s, float x);

/// floor(n * i / parts) without overflow (0 <= i <= parts): where part i of a batch of n
/// begins when it is cut in `parts` shares.
uint64_t share_of(uint64_t n, int i, int parts);

/// Calls row(place, values) for each line of part `part` of `parts` of the CSV file `in` of
/// `columns` (line 1 names them, see parse_header), `values` one per column of `columns` in its
/// order, the defaults for the ones the file lacks. A part's lines are those that start in its
/// share of the bytes after line 1; the lines before them are read but not parsed, so that
/// line numbers and the blank-line rule are the whole file's. Throws rp::Error
/// "<path>: line N: ..." for a bad header, a line with the wrong number of values or a blank
/// line before the end; what row() throws goes through.
void read_rows(InputFile& in, const Columns& columns, int part, int parts,
               const std::function<void(const Place& at, const std::string_view* values)>& row);

}  // namespace rp::csv
