#include "io/rayfile.h"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string_view>
#include <system_error>

#include "base/error.h"
#include "base/text.h"
#include "io/input_file.h"
#include "io/output_file.h"

namespace rp {

namespace {

// The binary formats are little-endian IEEE-754; this build stores floats as they are in memory.
static_assert(std::endian::native == std::endian::little, "rayfile.cpp assumes a little-endian machine");
static_assert(std::numeric_limits<float>::is_iec559 && sizeof(float) == 4, "float must be IEEE-754 binary32");
static_assert(sizeof(HitRecord) == 32, "HitRecord is 32 bytes");

constexpr size_t kHeaderBytes = 16;
constexpr size_t kChunkRecords = 4096;  // records decoded or encoded per read / write call

/// What tells the binary formats apart: the magic, and the version (with its record size).
struct BinaryFormat {
  const char* magic;      // 4 ASCII bytes
  const char* kind;       // "ray" / "hit" in "not a raypack ray file"
  const char* one;        // noun for a count of 1
  const char* many;       // noun for other counts
  uint32_t version;       // the version this writer writes
  size_t record_bytes;    // of that version
  uint32_t old_version;   // an older version still read (0: none)
  size_t old_record_bytes;
};
constexpr BinaryFormat kRayFormat{"RPRY", "ray", "ray", "rays", 1, 32, 0, 0};
/// Version 2 added instance_id to each record; version 1's 28-byte records are still read.
constexpr BinaryFormat kHitFormat{"RPHT", "hit", "hit", "hits", 2, 32, 1, 28};

/// The columns of a CSV file of one kind, in the order the writer writes them (line 1 of a
/// written file is these names joined by commas); the first `required` must be in every file,
/// the others default to `defaults` (text parsed like a value; null for required columns).
struct CsvColumns {
  std::array<const char*, 8> names;
  size_t count, required;
  std::array<const char*, 8> defaults;
};
constexpr CsvColumns kRayColumns{{"ox", "oy", "oz", "dx", "dy", "dz", "tnear", "tfar"}, 8, 6,
                                 {nullptr, nullptr, nullptr, nullptr, nullptr, nullptr, "0", "inf"}};
constexpr CsvColumns kHitColumns{{"t", "prim_id", "u", "v", "ng_x", "ng_y", "ng_z", "instance_id"}, 8, 7,
                                 {nullptr, nullptr, nullptr, nullptr, nullptr, nullptr, nullptr, "-1"}};

std::string errno_message(int e) { return std::generic_category().message(e); }

/// The format `path` names for a file of `fmt`'s kind: .csv (any case) CSV; .bin, .rays /
/// .hits or no extension (devices such as /dev/stdout) binary; any other extension an error.
bool is_csv(const std::string& path, const BinaryFormat& fmt) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".csv") return true;
  if (ext.empty() || ext == ".bin" || ext == std::string(".") + fmt.many) return false;
  throw Error(cat(path, ": unknown ", fmt.kind, " file extension '", printable(ext), "' (.csv for text; .bin, .", fmt.many,
                  " or none for binary)"));
}

/// `text` without blanks (spaces, tabs) at either end.
std::string_view trim(std::string_view text) {
  const size_t first = text.find_first_not_of(" \t");
  if (first == std::string_view::npos) return {};
  return text.substr(first, text.find_last_not_of(" \t") - first + 1);
}

/// The fields of one CSV line, blanks around each value dropped.
std::vector<std::string_view> split_csv(std::string_view line) {
  std::vector<std::string_view> out;
  for (size_t start = 0;;) {
    const size_t comma = line.find(',', start);
    out.push_back(trim(line.substr(start, comma == std::string_view::npos ? comma : comma - start)));
    if (comma == std::string_view::npos) return out;
    start = comma + 1;
  }
}

/// Line 1 of a CSV file of `columns`: for each column of the file, the field it holds. The
/// line may start with a UTF-8 byte order mark (spreadsheets) and '#' (numpy.savetxt's
/// header), and names may have blanks around them. Returns an empty vector with `why` set when
/// the line is no such header.
std::vector<size_t> parse_header(std::string_view line, const CsvColumns& columns, std::string& why) {
  const std::string expected = [&] {
    std::string all;
    for (size_t f = 0; f < columns.count; ++f) all += cat(f ? "," : "", columns.names[f]);
    return all;
  }();
  if (line.starts_with("\xEF\xBB\xBF")) line.remove_prefix(3);
  line = trim(line);
  if (line.starts_with('#')) line = trim(line.substr(1));
  std::vector<size_t> field;
  std::array<bool, 8> seen{};
  for (const std::string_view name : split_csv(line)) {
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
                      columns.names[columns.required], columns.count - columns.required > 1 ? " and the ones after it" : "",
                      " are needed)");
      return {};
    }
  return field;
}

/// floor(n * i / parts) without overflow (i <= parts).
uint64_t share_of(uint64_t n, int i, int parts) {
  const uint64_t p = uint64_t(parts), k = uint64_t(i);
  return n / p * k + n % p * k / p;
}

/// count * k in decimal, exact even when the product does not fit in 64 bits.
std::string times(uint64_t count, uint64_t k) {
  if (k == 0 || count <= UINT64_MAX / k) return std::to_string(count * k);
  std::string digits = std::to_string(count);
  uint64_t carry = 0;
  for (auto it = digits.rbegin(); it != digits.rend(); ++it) {
    const uint64_t x = uint64_t(*it - '0') * k + carry;
    *it = char('0' + x % 10);
    carry = x / 10;
  }
  for (; carry != 0; carry /= 10) digits.insert(digits.begin(), char('0' + carry % 10));
  return digits;
}

/// An input opened for reading by the rule of io/input_file.h (a regular file), or standard
/// input for "-", read whole into memory first; closed on scope exit.
class InputFile {
 public:
  explicit InputFile(const std::string& path) : path_(path) {
    if (path == "-") {
      memory_ = read_file(path, /*allow_stdin=*/true);
      f_ = ::fmemopen(memory_.data(), memory_.size(), "rb");
      if (!f_) throw Error(cat("standard input: cannot read: ", errno_message(errno)));
      size_ = memory_.size();
      return;
    }
    const int fd = open_regular_file(path, size_);
    f_ = ::fdopen(fd, "rb");
    if (!f_) {
      const int e = errno;
      ::close(fd);
      throw Error(cat(path, ": cannot open: ", errno_message(e)));
    }
  }
  ~InputFile() {
    if (f_) std::fclose(f_);
  }
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;

  std::FILE* get() const { return f_; }
  const std::string& path() const { return path_; }
  uint64_t size() const { return size_; }
  /// The bytes of standard input ("-"); empty for a file.
  const std::string& memory() const { return memory_; }

  /// Throws for a stream error after a short read at byte `offset`.
  [[noreturn]] void fail_read(uint64_t offset) const {
    if (std::ferror(f_)) throw Error(cat(path_, ": read error at byte ", offset, ": ", errno_message(errno)));
    throw Error(cat(path_, ": truncated at byte ", offset, " (the file shrank while it was read)"));
  }

 private:
  std::string path_;
  std::string memory_;
  std::FILE* f_ = nullptr;
  uint64_t size_ = 0;
};

/// True when `in` is CSV: by the extension of its path, or for standard input ("-") by its
/// first line being a header of `columns`.
bool is_csv(const InputFile& in, const BinaryFormat& fmt, const CsvColumns& columns) {
  if (in.path() != "-") return is_csv(in.path(), fmt);
  const std::string_view text = in.memory();
  std::string why;
  return !parse_header(text.substr(0, text.find('\n')), columns, why).empty();
}

/// The bytes of a binary file, read in order; their total is known up front.
class ByteSource {
 public:
  explicit ByteSource(InputFile& in) : in_(in) {}

  uint64_t size() const { return in_.size(); }

  /// Reads the next n bytes; callers never ask past size().
  void read(unsigned char* dst, size_t n) {
    if (std::fread(dst, 1, n, in_.get()) != n) in_.fail_read(offset_);
    offset_ += n;
  }
  /// Moves past the next n bytes without reading them.
  void skip(uint64_t n) {
    if (n > 0 && ::fseeko(in_.get(), off_t(offset_ + n), SEEK_SET) != 0) in_.fail_read(offset_);
    offset_ += n;
  }

 private:
  InputFile& in_;
  uint64_t offset_ = 0;
};

uint32_t load_u32(const unsigned char* p) {
  uint32_t v;
  std::memcpy(&v, p, 4);
  return v;
}
uint64_t load_u64(const unsigned char* p) {
  uint64_t v;
  std::memcpy(&v, p, 8);
  return v;
}

/// Reads the records of `part` of a binary file of `fmt` (its version or the old one it still
/// reads), decoding each record with decode(bytes, version, Record&).
template <typename Record, typename Decode>
std::vector<Record> read_binary(InputFile& in, const BinaryFormat& fmt, Decode decode, FilePart part) {
  const std::string& path = in.path();
  ByteSource src(in);
  const uint64_t size = src.size();
  unsigned char header[kHeaderBytes] = {};
  src.read(header, size_t(std::min<uint64_t>(size, kHeaderBytes)));
  if (size >= 4 && std::memcmp(header, fmt.magic, 4) != 0)
    throw Error(cat(path, ": not a raypack ", fmt.kind, " file (magic '",
                    printable({reinterpret_cast<const char*>(header), 4}), "', expected '", fmt.magic, "')"));
  if (size < kHeaderBytes)
    throw Error(cat(path, ": truncated: ", size, " bytes, the header needs ", kHeaderBytes));
  const uint32_t version = load_u32(header + 4);
  if (version != fmt.version && (fmt.old_version == 0 || version != fmt.old_version))
    throw Error(cat(path, ": unsupported version ", version, " (",
                    fmt.old_version ? cat(fmt.old_version, " or ", fmt.version) : cat(fmt.version), ")"));
  const size_t record_bytes = version == fmt.version ? fmt.record_bytes : fmt.old_record_bytes;
  const uint64_t count = load_u64(header + 8);
  const uint64_t follow = size - kHeaderBytes;
  // Checked before anything is allocated: a corrupt count must not reserve memory.
  if (count > follow / record_bytes || count * record_bytes != follow)
    throw Error(cat(path, ": the header declares ", count, " ", count == 1 ? fmt.one : fmt.many, " (",
                    times(count, record_bytes), " bytes) but ", follow, " bytes follow it"));

  const RecordRange range = part_records(count, part);
  src.skip(range.first * record_bytes);
  std::vector<Record> out(static_cast<size_t>(range.last - range.first));
  std::vector<unsigned char> chunk(kChunkRecords * record_bytes);
  for (size_t first = 0; first < out.size(); first += kChunkRecords) {
    const size_t n = std::min(kChunkRecords, out.size() - first);
    src.read(chunk.data(), n * record_bytes);
    for (size_t i = 0; i < n; ++i) decode(chunk.data() + i * record_bytes, version, out[first + i]);
  }
  return out;
}

// Records are copied field by field with memcpy so every bit pattern (signalling NaNs
// included) is kept.
void decode_ray(const unsigned char* p, uint32_t, Ray& r) {
  std::memcpy(&r.org.x, p + 0, 4);
  std::memcpy(&r.org.y, p + 4, 4);
  std::memcpy(&r.org.z, p + 8, 4);
  std::memcpy(&r.dir.x, p + 12, 4);
  std::memcpy(&r.dir.y, p + 16, 4);
  std::memcpy(&r.dir.z, p + 20, 4);
  std::memcpy(&r.tnear, p + 24, 4);
  std::memcpy(&r.tfar, p + 28, 4);
}
void encode_ray(const Ray& r, unsigned char* p) {
  std::memcpy(p + 0, &r.org.x, 4);
  std::memcpy(p + 4, &r.org.y, 4);
  std::memcpy(p + 8, &r.org.z, 4);
  std::memcpy(p + 12, &r.dir.x, 4);
  std::memcpy(p + 16, &r.dir.y, 4);
  std::memcpy(p + 20, &r.dir.z, 4);
  std::memcpy(p + 24, &r.tnear, 4);
  std::memcpy(p + 28, &r.tfar, 4);
}
void decode_hit(const unsigned char* p, uint32_t version, HitRecord& h) {
  std::memcpy(&h.t, p + 0, 4);
  std::memcpy(&h.prim_id, p + 4, 4);
  std::memcpy(&h.u, p + 8, 4);
  std::memcpy(&h.v, p + 12, 4);
  std::memcpy(&h.ng.x, p + 16, 4);
  std::memcpy(&h.ng.y, p + 20, 4);
  std::memcpy(&h.ng.z, p + 24, 4);
  h.instance_id = kNoInstance;
  if (version >= 2) std::memcpy(&h.instance_id, p + 28, 4);
}
void encode_hit(const HitRecord& h, unsigned char* p) {
  std::memcpy(p + 0, &h.t, 4);
  std::memcpy(p + 4, &h.prim_id, 4);
  std::memcpy(p + 8, &h.u, 4);
  std::memcpy(p + 12, &h.v, 4);
  std::memcpy(p + 16, &h.ng.x, 4);
  std::memcpy(p + 20, &h.ng.y, 4);
  std::memcpy(p + 24, &h.ng.z, 4);
  std::memcpy(p + 28, &h.instance_id, 4);
}

/// The 16-byte header of a binary file of `fmt` with `count` records.
std::string binary_head(const BinaryFormat& fmt, uint64_t count) {
  unsigned char header[kHeaderBytes];
  std::memcpy(header, fmt.magic, 4);
  std::memcpy(header + 4, &fmt.version, 4);
  std::memcpy(header + 8, &count, 8);
  return {reinterpret_cast<const char*>(header), kHeaderBytes};
}

/// Appends `records` to `out` as binary records of `fmt`, each encoded by encode(record, bytes).
template <typename Record, typename Encode>
void append_binary(std::span<const Record> records, const BinaryFormat& fmt, Encode encode, std::string& out) {
  const size_t at = out.size();
  out.resize(at + records.size() * fmt.record_bytes);
  for (size_t i = 0; i < records.size(); ++i)
    encode(records[i], reinterpret_cast<unsigned char*>(out.data() + at + i * fmt.record_bytes));
}

/// Writes `head`, then the records, kChunkRecords at a time, each chunk's bytes made by
/// append(chunk, bytes).
template <typename Record, typename Append>
void write_records(const std::string& path, const std::string& head, std::span<const Record> records, Append append) {
  OutputFile out(path);
  out.write(head.data(), head.size());
  std::string bytes;
  for (size_t first = 0; first < records.size(); first += kChunkRecords) {
    bytes.clear();
    append(records.subspan(first, std::min(kChunkRecords, records.size() - first)), bytes);
    out.write(bytes.data(), bytes.size());
  }
  out.commit();
}

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

/// Where a CSV value came from, for messages.
struct CsvPlace {
  const std::string& path;
  uint64_t line;
};

float parse_float(const CsvPlace& at, std::string_view s) {
  float v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || end != s.data() + s.size() || ec == std::errc::invalid_argument)
    throw Error(cat(at.path, ": line ", at.line, ": '", printable(s), "' is not a number"));
  if (ec == std::errc::result_out_of_range)
    throw Error(cat(at.path, ": line ", at.line, ": '", printable(s), "' is out of the float32 range"));
  return v;
}

/// A prim_id or instance_id (`what`): a decimal integer in [-1, 0xfffffffe], -1 for
/// 0xffffffff (kInvalidId, kNoInstance).
uint32_t parse_id(const CsvPlace& at, std::string_view s, const char* what) {
  int64_t v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || end != s.data() + s.size() || ec != std::errc() || v < -1 || v >= int64_t(kInvalidId))
    throw Error(cat(at.path, ": line ", at.line, ": '", printable(s), "' is not ", what));
  return v == -1 ? kInvalidId : uint32_t(v);
}

/// Reads `part` of a CSV file of `columns` (line 1 names them, see parse_header; every other
/// line holds one value per column), each line turned into a Record by make(place, values), the
/// values in the order of `columns` with the defaults for absent ones. The part's lines are
/// those that start in its share of the bytes after line 1; the lines before them are read
/// but not parsed, so that line numbers and the blank-line rule are the whole file's.
template <typename Record, typename Make>
std::vector<Record> read_csv(InputFile& in, const CsvColumns& columns, Make make, FilePart part) {
  const std::string& path = in.path();
  LineReader lines(in);
  std::string_view line;
  std::string why = "empty file: expected a header naming the columns";
  const std::vector<size_t> field = lines.next(line) ? parse_header(line, columns, why) : std::vector<size_t>();
  if (field.empty()) throw Error(cat(path, ": line 1: ", why));
  const uint64_t body = lines.offset(), share = in.size() - std::min(in.size(), body);
  const uint64_t begin = body + share_of(share, part.index, part.count);
  const uint64_t end = part.index + 1 == part.count ? UINT64_MAX : body + share_of(share, part.index + 1, part.count);
  std::vector<Record> out;
  uint64_t blank = 0;  // first blank line seen; fine only if nothing follows it
  std::string_view values[8];
  for (size_t f = columns.required; f < columns.count; ++f) values[f] = columns.defaults[f];
  while (lines.next(line) && lines.start() < end) {
    if (trim(line).empty()) {
      if (blank == 0) blank = lines.number();
      continue;
    }
    if (blank != 0) throw Error(cat(path, ": line ", blank, ": blank line before the end of the data"));
    if (lines.start() < begin) continue;
    const std::vector<std::string_view> v = split_csv(line);
    if (v.size() != field.size())
      throw Error(cat(path, ": line ", lines.number(), ": ", v.size(), v.size() == 1 ? " value" : " values", ", expected ",
                      field.size()));
    for (size_t c = 0; c < v.size(); ++c) values[field[c]] = v[c];
    out.push_back(make(CsvPlace{path, lines.number()}, values));
  }
  return out;
}

/// printf("%.9g") in the C locale whatever the global locale; every NaN is "nan".
void append_float(std::string& s, float x) {
  if (std::isnan(x)) {
    s += "nan";
    return;
  }
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, x, std::chars_format::general, 9);
  s.append(buf, r.ptr);
}

/// Line 1 of a CSV file of `columns`: their names.
std::string csv_head(const CsvColumns& columns) {
  std::string text;
  for (size_t f = 0; f < columns.count; ++f) text += cat(f ? "," : "", columns.names[f]);
  return text + '\n';
}

/// Appends `records` to `out` as CSV lines, each formed by line(record, text).
template <typename Record, typename Line>
void append_csv(std::span<const Record> records, Line line, std::string& out) {
  for (const Record& r : records) {
    line(r, out);
    out += '\n';
  }
}

void ray_line(const Ray& r, std::string& s) {
  const float v[8] = {r.org.x, r.org.y, r.org.z, r.dir.x, r.dir.y, r.dir.z, r.tnear, r.tfar};
  for (int i = 0; i < 8; ++i) {
    if (i) s += ',';
    append_float(s, v[i]);
  }
}

void hit_line(const HitRecord& h, std::string& s) {
  const auto id = [](uint32_t v) { return v == kInvalidId ? std::string("-1") : std::to_string(v); };
  append_float(s, h.t);
  s += ',' + id(h.prim_id);
  for (float x : {h.u, h.v, h.ng.x, h.ng.y, h.ng.z}) {
    s += ',';
    append_float(s, x);
  }
  s += ',' + id(h.instance_id);
}

}  // namespace

void check_ray_file_name(const std::string& path) {
  if (path != "-") is_csv(path, kRayFormat);
}

void check_hit_file_name(const std::string& path) {
  if (path != "-") is_csv(path, kHitFormat);
}

RecordRange part_records(uint64_t n, FilePart part) {
  RP_CHECK(part.count >= 1 && part.index >= 0 && part.index < part.count, "file part ", part.index, " of ", part.count);
  const auto bound = [&](int i) { return i == part.count ? n : share_of(n, i, part.count) / 8 * 8; };
  return {bound(part.index), bound(part.index + 1)};
}

std::vector<Ray> read_rays(const std::string& path) { return read_rays(path, FilePart{}); }

std::vector<Ray> read_rays(const std::string& path, FilePart part) {
  RP_CHECK(path != "-" || part.count == 1, "standard input cannot be read in parts");
  InputFile in(path);
  if (!is_csv(in, kRayFormat, kRayColumns)) return read_binary<Ray>(in, kRayFormat, decode_ray, part);
  return read_csv<Ray>(
      in, kRayColumns,
      [](const CsvPlace& at, const std::string_view* s) {
        Ray r;
        r.org = {parse_float(at, s[0]), parse_float(at, s[1]), parse_float(at, s[2])};
        r.dir = {parse_float(at, s[3]), parse_float(at, s[4]), parse_float(at, s[5])};
        r.tnear = parse_float(at, s[6]);
        r.tfar = parse_float(at, s[7]);
        return r;
      },
      part);
}

void write_rays(const std::string& path, std::span<const Ray> rays) {
  if (!is_csv(path, kRayFormat))
    return write_records(path, binary_head(kRayFormat, rays.size()), rays, [](std::span<const Ray> chunk, std::string& out) {
      append_binary(chunk, kRayFormat, encode_ray, out);
    });
  write_records(path, csv_head(kRayColumns), rays,
                [](std::span<const Ray> chunk, std::string& out) { append_csv(chunk, ray_line, out); });
}

std::vector<HitRecord> read_hits(const std::string& path) {
  InputFile in(path);
  if (!is_csv(in, kHitFormat, kHitColumns)) return read_binary<HitRecord>(in, kHitFormat, decode_hit, FilePart{});
  return read_csv<HitRecord>(
      in, kHitColumns,
      [](const CsvPlace& at, const std::string_view* s) {
        HitRecord h;
        h.t = parse_float(at, s[0]);
        h.prim_id = parse_id(at, s[1], "a primitive id");
        h.u = parse_float(at, s[2]);
        h.v = parse_float(at, s[3]);
        h.ng = {parse_float(at, s[4]), parse_float(at, s[5]), parse_float(at, s[6])};
        h.instance_id = parse_id(at, s[7], "an instance id");
        return h;
      },
      FilePart{});
}

std::string hit_file_head(const std::string& path, uint64_t count) {
  return is_csv(path, kHitFormat) ? csv_head(kHitColumns) : binary_head(kHitFormat, count);
}

void append_hit_records(const std::string& path, std::span<const HitRecord> hits, std::string& out) {
  if (is_csv(path, kHitFormat)) return append_csv(hits, hit_line, out);
  append_binary(hits, kHitFormat, encode_hit, out);
}

void write_hits(const std::string& path, std::span<const HitRecord> hits) {
  write_records(path, hit_file_head(path, hits.size()), hits,
                [&](std::span<const HitRecord> chunk, std::string& out) { append_hit_records(path, chunk, out); });
}

}  // namespace rp
