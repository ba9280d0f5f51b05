#include "io/pointfile.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>

#include "base/error.h"
#include "base/text.h"
#include "io/csv.h"
#include "io/input_file.h"
#include "io/output_file.h"

namespace rp {

namespace {

constexpr csv::Columns kPointColumns{{"x", "y", "z", "radius"}, 4, 3, {nullptr, nullptr, nullptr, "inf"}};
constexpr csv::Columns kClosestColumns{
    {"distance", "x", "y", "z", "prim_id", "geometry_id", "instance_id", "u", "v"}, 9, 9, {}};
constexpr csv::Columns kSignedColumns{
    {"distance", "x", "y", "z", "prim_id", "geometry_id", "instance_id", "u", "v", "signed_distance", "inside"},
    11,
    11,
    {}};

/// Records written per call to the output.
constexpr size_t kChunkRecords = 4096;

/// Appends `id` in decimal, kInvalidId as -1.
void append_id(std::string& s, uint32_t id) { s += id == kInvalidId ? std::string("-1") : std::to_string(id); }

void closest_line(const ClosestPointRecord& r, bool with_sign, std::string& s) {
  const ClosestPoint& c = r.closest;
  const float nan = std::nanf("");
  csv::append_float(s, c.distance);
  for (const float x : {c.point.x, c.point.y, c.point.z}) {
    s += ',';
    csv::append_float(s, c.found() ? x : nan);
  }
  for (const uint32_t id : {c.prim_id, r.geometry_id, c.instance_id}) {
    s += ',';
    append_id(s, id);
  }
  for (const float x : {c.u, c.v}) {
    s += ',';
    csv::append_float(s, x);
  }
  if (with_sign) {
    s += ',';
    csv::append_float(s, r.signed_distance);
    s += r.inside ? ",1" : ",0";
  }
  s += '\n';
}

}  // namespace

void check_point_file_name(const std::string& path) {
  if (path == "-") return;
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](char c) { return char(std::tolower(static_cast<unsigned char>(c))); });
  if (ext != ".csv" && !ext.empty())
    throw Error(cat(path, ": unknown point file extension '", printable(ext), "' (.csv: point files are text)"));
}

std::vector<PointQuery> read_points(const std::string& path) {
  check_point_file_name(path);
  InputFile in(path);
  std::vector<PointQuery> points;
  csv::read_rows(in, kPointColumns, 0, 1, [&](const csv::Place& at, const std::string_view* s) {
    PointQuery q;
    float* xyz[] = {&q.point.x, &q.point.y, &q.point.z};
    for (int k = 0; k < 3; ++k) {
      *xyz[k] = csv::parse_float(at, s[k]);
      if (!std::isfinite(*xyz[k]))
        throw Error(cat(path, ": line ", at.line, ": ", kPointColumns.names[k], " '", printable(s[k]),
                        "' is not a finite number"));
      if (std::abs(*xyz[k]) > kMaxCoordinate)
        throw Error(cat(path, ": line ", at.line, ": ", kPointColumns.names[k], " '", printable(s[k]),
                        "' is outside the supported coordinate range |x| <= 1073741824 (2^30)"));
    }
    q.radius = csv::parse_float(at, s[3]);
    if (!(q.radius >= 0.0f))
      throw Error(
          cat(path, ": line ", at.line, ": radius '", printable(s[3]), "' is not a distance (a number >= 0, or inf)"));
    points.push_back(q);
  });
  return points;
}

void write_closest_points(const std::string& path, std::span<const ClosestPointRecord> records, bool with_sign) {
  OutputFile out(path);
  std::string text = csv::head(with_sign ? kSignedColumns : kClosestColumns);
  for (size_t first = 0; first < records.size(); first += kChunkRecords) {
    for (const ClosestPointRecord& r : records.subspan(first, std::min(kChunkRecords, records.size() - first)))
      closest_line(r, with_sign, text);
    out.write(text.data(), text.size());
    text.clear();
  }
  out.write(text.data(), text.size());
  out.commit();
}

}  // namespace rp
