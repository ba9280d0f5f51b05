#pragma once
/// `raypack stability`: failure rates of intersection methods on ray families built where
/// methods fail (README: "Stability where methods fail").
///
/// Every family is a scene and a seeded set of float rays; the double-precision reference
/// (analysis/reference.h), exact for those float rays and float vertices, is the oracle. A
/// method is a backend method ("simd/watertight:stream", every family) or a scalar routine of
/// core/geometry/ (the families whose rays name the primitives they aim at: its "fan"). Each ray is classified
/// against the reference; see Counts for the failure kinds and classify() in stability.cpp
/// for the rules.

#include <cstdint>
#include <cstdio>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/backend.h"
#include "core/scene.h"

namespace rp::stability {

/// Failures of one method on one family. A ray counts once in `failed` and once in the
/// kind that failed it (the first in this order). Double hits are counted beside them, not
/// as failures: a ray through a shared edge or vertex meets every triangle there at the same
/// point, so a closed-interval (watertight) test reports it from several triangles; harmless
/// for a closest hit, wrong for anything that counts crossings (inside/outside parity).
struct Counts {
  uint64_t rays = 0;             ///< rays the method was judged on
  uint64_t failed = 0;           ///< rays with any failure
  uint64_t nan_hits = 0;         ///< a hit for a ray with NaN/Inf in it, or a non-finite t
  uint64_t out_of_interval = 0;  ///< a hit outside [tnear, tfar]
  uint64_t self_hits = 0;        ///< a ray leaving a surface hits the primitive it leaves
  uint64_t leaks = 0;            ///< the reference hits; the method misses or hits farther (passes through)
  uint64_t false_hits = 0;       ///< the method hits where the reference misses, or nearer than it
  uint64_t t_errors = 0;         ///< the reference's primitive, t beyond the tolerance
  uint64_t double_hits = 0;      ///< two or more primitives of the fan hit the same point (scalar
                                 ///< methods; not in `failed`)
  bool double_measured = false;  ///< double hits are observable (scalar routines only)

  double rate() const { return rays ? double(failed) / double(rays) : 0.0; }
};

/// One method on one family.
struct Result {
  std::string family;       ///< e.g. "edges", "translated"
  std::string param;        ///< e.g. "1e5" for the translated and scaled families, else ""
  int exponent = 0;         ///< k of 10^k for translated/scaled families
  bool has_exponent = false;
  std::string method;  ///< e.g. "simd/watertight:stream", "sphere/naive"
  Counts counts;
};

/// A backend built for one method, and the coherence hint that selects the method.
struct MethodBackend {
  std::unique_ptr<Backend> backend;
  Coherence coherence = Coherence::incoherent;
};

/// Builds the backend of a method ("backend/variant:method", backends/registry.h) over a
/// scene; the CLI passes one over the registry's make_backend.
using BackendFactory = std::function<MethodBackend(const std::string& method, const Scene& scene)>;

struct Options {
  uint32_t rays = 4096;  ///< rays per family
  uint64_t seed = 1;
  double t_tolerance = 1e-4;  ///< relative t difference beyond which a hit is wrong
  std::vector<std::string> backends{"embree/default:single", "embree/robust:single", "simd/default:stream",
                                    "simd/watertight:stream"};
  BackendFactory make_backend;
  /// Family names to run (empty: all); see family_names().
  std::vector<std::string> families;
  std::function<void(const std::string&)> progress;  ///< called before each family, may be empty
};

/// Names of the families, in the order run() produces them, each with a one-line description.
std::vector<std::pair<std::string, std::string>> family_names();

/// Names of the scalar methods (triangle, sphere and quadric routines).
std::vector<std::string> scalar_methods();

/// Runs every selected family on `scene` (its triangle meshes give the mesh families; the
/// analytic families build their own scenes) with every backend and scalar method that
/// applies. Deterministic for a seed. Throws rp::Error for an unknown family name.
std::vector<Result> run(const Scene& scene, const Options& options);

/// The table: one line per family × method.
void print_table(std::FILE* out, const std::vector<Result>& results);

/// The results as JSON text (an object with "results": [...] and the options used).
std::string to_json(const std::vector<Result>& results, const std::string& scene_name, const Options& options);

}  // namespace rp::stability
