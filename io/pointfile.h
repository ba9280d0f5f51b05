#pragma once
/// Point files: the query points `raypack points` reads and the closest points it writes
/// (core/queries.h). Text only, by the CSV rules of io/csv.h; the name ends in `.csv` (any
/// case), or has no extension (a device such as /dev/stdout); "-" reads standard input.
///
/// Query points: line 1 names the columns `x,y,z` and optionally `radius` (in any order),
/// each following line one point: its coordinates, finite and within the coordinate range
/// |x| <= 2^30 (core/ray.h), and the largest distance of interest, a number >= 0 or `inf`
/// (inf when the column is absent). Anything else is refused with one line naming the file,
/// the line and the value: `points.csv: line 4: y 'nan' is not a finite number`.
///
/// Closest points: line 1 `distance,x,y,z,prim_id,geometry_id,instance_id,u,v`, then a line
/// per query point in the input's order: the distance to the closest point of the surface,
/// that point, its primitive, geometry and instance (-1: none) and (u, v) (ClosestPoint).
/// With no surface within the radius: `inf,nan,nan,nan,-1,-1,-1,0,0`. With the signed
/// columns, two more: `signed_distance` (the distance, negative inside; -inf inside with no
/// surface within the radius) and `inside` (1 or 0, rp::inside). Floats as `%.9g`.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/queries.h"

namespace rp {

/// One answer of a closest-point query as a point file holds it.
struct ClosestPointRecord {
  ClosestPoint closest;
  uint32_t geometry_id = kInvalidId;  ///< Scene::geometry_of(closest.prim_id); kInvalidId when not found
  float signed_distance = 0.0f;       ///< written only with the signed columns
  bool inside = false;
};

/// Throws rp::Error naming `path` when it cannot name a point file (see the top of this
/// header): `points.txt: unknown point file extension '.txt' (.csv: point files are text)`.
void check_point_file_name(const std::string& path);

/// The query points of the point file `path` ("-": standard input). Throws rp::Error naming
/// the file and the line (see the top of this header).
std::vector<PointQuery> read_points(const std::string& path);

/// Writes the closest points to `path` by rp::OutputFile (complete or absent), with the
/// columns `signed_distance,inside` when `with_sign`.
void write_closest_points(const std::string& path, std::span<const ClosestPointRecord> records, bool with_sign);

}  // namespace rp
