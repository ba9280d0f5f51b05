#pragma once
// The Pareto chart of speed and exactness: each backend method's throughput on ordinary rays
// (a `raypack bench` file) against its failure rate on the ray families where methods fail
// (a `raypack stability` file), so the methods that no other beats on both axes show as one
// front.

#include <map>
#include <nlohmann/json.hpp>
#include <string>

namespace rp::cli {

/// The families whose pooled failure rate is the chart's accuracy axis: shared edges, shared
/// vertices, the scene translated by 10^6, and grazing rays (`raypack stability --list`).
inline constexpr const char* kHardFamilies = "edges, vertices, translated 1e6, grazing";

/// Failed and total rays of one method over the hard families.
struct HardFailures {
  double failed = 0, rays = 0;
};

/// The stability file at `path` read for the chart: backend variant (the "backend/variant" of
/// each method "backend/variant:method") -> its failures over the hard families, pooled over
/// the variant's methods. Throws rp::Error naming the file when it is not a stability file or holds none
/// of the hard families (so `raypack bench --stability` can refuse it before timing).
std::map<std::string, HardFailures> read_hard_failures(const std::string& path);

/// Draws <dir>/<stem>-pareto<ext> beside `chart` (.png or .svg by its extension): a panel per
/// ray kind of `bench`, x the rate (million rays a second) of each backend variant (bench's
/// "backend" key, e.g. simd/watertight: its fastest method for that kind, geometric mean over
/// the file's scenes), y the failed rays over all rays of the hard families in the stability
/// file at `stability_path` for that variant's methods; one point per variant in both files,
/// named in a legend, the Pareto front (no other point both faster and as exact) joined by a
/// line. Throws rp::Error naming the stability file as read_hard_failures does, or when it
/// shares no variant with the bench results. Returns the file written.
std::string draw_pareto(const nlohmann::ordered_json& bench, const std::string& stability_path, const std::string& chart);

}  // namespace rp::cli
