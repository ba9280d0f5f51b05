#include "mpi/diff_ranks.h"

#include <vector>

#include "analysis/reference.h"
#include "mpi/ray_parts.h"
#include "mpi/select.h"

namespace rp::dist {

namespace {

/// The statistics of every rank's `samples` together, as summarize() finds them in one process.
ErrorStats summarize_across(const Comm& comm, const ErrorSamples& samples) {
  uint64_t n[] = {samples.t_rel.size()};
  comm.sum(n);
  ErrorStats s;
  s.rays = n[0];
  if (n[0] == 0) return s;
  s.t_p50 = select_across(comm, samples.t_rel, percentile_index(n[0], 0.50));
  s.t_p99 = select_across(comm, samples.t_rel, percentile_index(n[0], 0.99));
  s.t_max = select_across(comm, samples.t_rel, n[0] - 1);
  s.angle_p99 = select_across(comm, samples.angle_deg, percentile_index(n[0], 0.99));
  s.angle_max = select_across(comm, samples.angle_deg, n[0] - 1);
  return s;
}

}  // namespace

DiffResult combine_across(const Comm& comm, DiffResult local) {
  std::vector<uint64_t> counts{local.rays};
  for (int c = 0; c < kDiffClasses; ++c) {
    const Support& p = local.support[size_t(c)];
    counts.insert(counts.end(), {local.count[size_t(c)], p.a, p.b, p.both, p.neither});
  }
  comm.sum(counts);
  local.rays = counts[0];
  for (size_t c = 0, at = 1; c < size_t(kDiffClasses); ++c, at += 5) {
    local.count[c] = counts[at];
    local.support[c] = {counts[at + 1], counts[at + 2], counts[at + 3], counts[at + 4]};
  }
  if (local.has_reference) {
    local.a_vs_reference = summarize_across(comm, local.a_samples);
    local.b_vs_reference = summarize_across(comm, local.b_samples);
  }
  return local;
}

std::vector<Hit> reference_hits_across(const Comm& comm, const Scene& scene, std::span<const Ray> rays) {
  const std::vector<Hit> mine = together(comm, [&] {
    const RecordRange range = share(comm, rays.size());
    const std::span<const Ray> part = rays.subspan(range.first, range.last - range.first);
    std::vector<ReferenceHit> rh(part.size());
    Reference(scene).intersect(part, rh);
    std::vector<Hit> hits(part.size());
    for (size_t i = 0; i < rh.size(); ++i) hits[i] = to_hit(rh[i]);
    return hits;
  });
  return gather_vector(comm, std::span<const Hit>(mine), true);
}

}  // namespace rp::dist
