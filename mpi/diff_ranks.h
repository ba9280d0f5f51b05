#pragma once
/// raypack diff across ranks: each rank diffs its share of the rays, and the shares' results
/// are combined into the one a single process finds for all the rays.

#include <span>
#include <vector>

#include "analysis/diff.h"
#include "mpi/comm.h"

namespace rp::dist {

/// `local`, the diff of this rank's share of the rays, combined with every other rank's:
/// counts and the reference's support summed, and the error statistics of the union of every
/// rank's samples (percentiles by select_across: the values one process finds, not averages of
/// the ranks'). per_ray and the samples stay this rank's own. Collective; the same on every rank.
DiffResult combine_across(const Comm& comm, DiffResult local);

/// The double-precision reference's closest hits of `rays` (the same batch on every rank) as
/// Hits: t, u, v rounded to float, the miss value where it misses. Each rank traces its share()
/// and every rank receives all. Collective; a failure throws on every rank.
std::vector<Hit> reference_hits_across(const Comm& comm, const Scene& scene, std::span<const Ray> rays);

}  // namespace rp::dist
