#include "io/csv.h"

#include <unistd.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <system_error>

#include "base/error.h"
#include "base/text.h"

namespace rp::csv {

namespace {

/// Lines of a text file without their "\n" or "\r\n", numbered from 1.
class LineReader {
 public:
  explicit LineReader(InputFile& in) : in_(in) {}
  ~LineReader() { std::free(buf_); }
  LineReader(const LineReader&) = delete;
  LineReader& operator=(const LineReader&) = delete;

  /// The next line, or false at the end of the file.
  bool next(std::string_view& line) {
    start_ = offset_;
    const ssize_t n = ::getline(&buf_, &cap_, in_.get());
    if (n < 0) {
      if (std::ferror(in_.get())) in_.fail_read(offset_);
      return false;
    }
    offset_ += uint64_t(n);
    ++number_;
    line = std::string_view(buf_, size_t(n));
    if (!line.empty() && line.back() == '\n') line.remove_suffix(1);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    return true;
  }
  uint64_t number() const { return number_; }
  /// The byte offset of the last line read, and of the next.
  uint64_t start() const { return start_; }
  uint64_t offset() const { return offset_; }

 private:
  InputFile& in_;
  char* buf_ = nullptr;
  size_t cap_ = 0;
  uint64_t number_ = 0, start_ = 0, offset_ = 0;
};

}  // namespace

std::string_view trim(std::string_view text) {
  const size_t first = text.find_first_not_of(" \t");
  if (first == std::string_view::npos) return {};
  return text.substr(first, text.find_last_not_of(" \t") - first + 1);
}

std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> out;
  for (size_t start = 0;;) {
    const size_t comma = line.find(',', start);
    out.push_back(trim(line.substr(start, comma == std::string_view::npos ? comma : comma - start)));
    if (comma == std::string_view::npos) return out;
    start = comma + 1;
  }
}

std::vector<size_t> parse_header(std::string_view line, const Columns& columns, std::string& why) {
  std::string expected = head(columns);
  expected.pop_back();  // its "\n"
  if (line.starts_with("\xEF\xBB\xBF")) line.remove_prefix(3);
  line = trim(line);
  if (line.starts_with('#')) line = trim(line.substr(1));
  std::vector<size_t> field;
  std::array<bool, kMaxColumns> seen{};
  for (const std::string_view name : split(line)) {
    size_t f = 0;
    while (f < columns.count && name != columns.names[f]) ++f;
    if (f == columns.count) {
      why = field.empty() ? cat("expected a header naming the columns (", expected, ")")
                          : cat("unknown column '", printable(name), "' (columns: ", expected, ")");
      return {};
    }
    if (seen[f]) {
      why = cat("column '", name, "' appears twice");
      return {};
    }
    seen[f] = true;
    field.push_back(f);
  }
  for (size_t f = 0; f < columns.required; ++f)
    if (!seen[f]) {
      why = columns.required == columns.count
                ? cat("no column '", columns.names[f], "' (columns: ", expected, ")")
                : cat("no column '", columns.names[f], "' (columns: ", expected, "; all but ",
                      columns.names[columns.required],
                      columns.count - columns.required > 1 ? " and the ones after it" : "", " are needed)");
      return {};
    }
  return field;
}

std::string head(const Columns& columns) {
  std::string text;
  for (size_t f = 0; f < columns.count; ++f) text += cat(f ? "," : "", columns.names[f]);
  return text + '\n';
}

float parse_float(const Place& at, std::string_view s) {
  float v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || end != s.data() + s.size() || ec == std::errc::invalid_argument)
    throw Error(cat(at.path, ": line ", at.line, ": '", printable(s), "' is not a number"));
  if (ec == std::errc::result_out_of_range)
    throw Error(cat(at.path, ": line ", at.line, ": '", printable(s), "' is out of the float32 range"));
  return v;
}

void append_float(std::string& s, float x) {
  if (std::isnan(x)) {
    s += "nan";
    return;
  }
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, x, std::chars_format::general, 9);
  s.append(buf, r.ptr);
}

uint64_t share_of(uint64_t n, int i, int parts) {
  const uint64_t p = uint64_t(parts), k = uint64_t(i);
  return n / p * k + n % p * k / p;
}

void read_rows(InputFile& in, const Columns& columns, int part, int parts,
               const std::function<void(const Place& at, const std::string_view* values)>& row) {
  const std::string& path = in.path();
  LineReader lines(in);
  std::string_view line;
  std::string why = "empty file: expected a header naming the columns";
  const std::vector<size_t> field = lines.next(line) ? parse_header(line, columns, why) : std::vector<size_t>();
  if (field.empty()) throw Error(cat(path, ": line 1: ", why));
  const uint64_t body = lines.offset(), share = in.size() - std::min(in.size(), body);
  const uint64_t begin = body + share_of(share, part, parts);
  const uint64_t end = part + 1 == parts ? UINT64_MAX : body + share_of(share, part + 1, parts);
  uint64_t blank = 0;  // first blank line seen; fine only if nothing follows it
  std::array<std::string_view, kMaxColumns> values;
  for (size_t f = columns.required; f < columns.count; ++f) values[f] = columns.defaults[f];
  while (lines.next(line) && lines.start() < end) {
    if (trim(line).empty()) {
      if (blank == 0) blank = lines.number();
      continue;
    }
    if (blank != 0) throw Error(cat(path, ": line ", blank, ": blank line before the end of the data"));
    if (lines.start() < begin) continue;
    const std::vector<std::string_view> v = split(line);
    if (v.size() != field.size())
      throw Error(cat(path, ": line ", lines.number(), ": ", v.size(), v.size() == 1 ? " value" : " values",
                      ", expected ", field.size()));
    for (size_t c = 0; c < v.size(); ++c) values[field[c]] = v[c];
    row(Place{path, lines.number()}, values.data());
  }
}

}  // namespace rp::csv
