#pragma once
/// Correctness diffing: the same rays through backends A and B and the double-precision
/// reference, classified ray by ray, summarised as a table, JSON and a mismatch image.

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "analysis/raygen.h"
#include "analysis/reference.h"
#include "core/scene.h"
#include "render/render.h"

namespace rp {

/// How A's and B's answers for one ray relate. "The same primitive" means the same prim_id in
/// the same instance (Hit::instance_id): one triangle of an instanced mesh hit through two
/// placements is two primitives (a tie at the same t, else a wrong primitive).
enum class DiffClass : uint8_t {
  agree,       ///< both miss, or the same primitive at t within t_tolerance
  tie,         ///< different primitives at t within tie_tolerance (a shared edge or vertex)
  hit_miss,    ///< one hits, the other misses
  wrong_prim,  ///< different primitives at different t
  t_error,     ///< the same primitive, t beyond t_tolerance
};
inline constexpr int kDiffClasses = 5;
const char* to_string(DiffClass c);

struct DiffOptions {
  double tie_tolerance = 1e-6;  ///< relative t difference that still makes a tie
  double t_tolerance = 1e-4;    ///< relative t difference allowed on the same primitive
};

/// Which answer the reference supports, for the rays of one class.
struct Support {
  size_t a = 0, b = 0, both = 0, neither = 0;
};

/// Error of one backend against the reference over the rays where both hit the same
/// primitive: relative t error |t - t_ref| / t_ref and the angle (degrees) between the
/// geometric normals at the two hit points.
struct ErrorStats {
  size_t rays = 0;
  double t_p50 = 0, t_p99 = 0, t_max = 0;
  double angle_p99 = 0, angle_max = 0;
};

/// The values ErrorStats summarises, one of each per ray where the backend hits the
/// reference's primitive (in ray order until summarize() reorders them).
struct ErrorSamples {
  std::vector<double> t_rel;      ///< |t - t_ref| / t_ref
  std::vector<double> angle_deg;  ///< angle between the geometric normals
};

/// Which of n sorted values (n > 0) is percentile p (in [0, 1]): the nearest rank,
/// p * (n - 1) rounded half up, at most n - 1.
size_t percentile_index(size_t n, double p);

/// p50, p99 and max of the samples (reordering them).
ErrorStats summarize(ErrorSamples& samples);

struct DiffResult {
  size_t rays = 0;
  std::array<size_t, kDiffClasses> count{};
  std::array<Support, kDiffClasses> support{};  ///< empty when no reference was given
  bool has_reference = false;
  ErrorStats a_vs_reference, b_vs_reference;
  /// What a_vs_reference and b_vs_reference summarise (for combining the diffs of several
  /// processes: raypack diff across MPI ranks).
  ErrorSamples a_samples, b_samples;
  std::vector<DiffClass> per_ray;

  /// Fraction of rays that agree or tie, in [0, 1] (1 for no rays).
  double agreement() const;
};

/// Classifies every ray: hits_a[i], hits_b[i] and (when not empty) reference[i] for rays[i].
DiffResult diff_hits(const Scene& scene, std::span<const Ray> rays, std::span<const Hit> hits_a,
                     std::span<const Hit> hits_b, std::span<const ReferenceHit> reference, const DiffOptions& options);

/// The readable summary: counts and rates per class, which side the reference supports, and
/// the error statistics; `a` and `b` name the two sides.
std::string format_table(const DiffResult& d, const std::string& a, const std::string& b);

/// The same as JSON (nlohmann::json dumped with 2-space indent).
std::string to_json(const DiffResult& d, const std::string& scene, const std::string& rays, const std::string& a,
                    const std::string& b, const DiffOptions& options);

/// One pixel per ray of `set` (which must carry pixels), coloured by class: agree dark grey
/// (black where both miss), tie yellow, hit/miss red, wrong primitive magenta, t error orange;
/// disagreements drawn 3x3 pixels wide so that one ray is visible.
Image mismatch_image(const DiffResult& d, const RaySet& set, std::span<const Hit> hits_a);

}  // namespace rp
