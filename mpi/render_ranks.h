#pragma once
/// A render across ranks (raypack render under mpirun): each rank has loaded the scene and
/// built its backend (replicated data, sort-first), renders with all its threads the tiles
/// rank 0 hands it (Comm::hand_out: dynamic load balancing), and rank 0 gathers them. A
/// tile's pixels depend on the inputs and its number only (TileRenderer), so the image is the
/// one a single process renders, bit for bit, whatever the ranks, threads and hand-out.

#include <cstdint>
#include <vector>

#include "mpi/comm.h"
#include "render/render.h"

namespace rp::dist {

/// What one rank did in a render across ranks.
struct RankRender {
  uint64_t tiles = 0;    ///< tiles it rendered
  int threads = 0;       ///< its worker threads
  double seconds = 0;    ///< from the start of the hand-out to its last tile
  HandoutStats handout;  ///< its requests to rank 0 and the time its threads waited for them
};

struct RenderAcross {
  Image image;                    ///< on rank 0 the whole image; empty elsewhere
  TileCounts counts;              ///< the rays of every rank, on every rank
  std::vector<RankRender> ranks;  ///< on rank 0 each rank's part, by rank; empty elsewhere
};

/// Renders every tile of `tiles` across the ranks of `comm` and gathers the image on rank 0.
/// `per_request`: tiles per request to rank 0 (0: guided, see Comm::hand_out); `progress`
/// (called on rank 0 only) gets the fraction of all ranks' tiles done. Collective; a failure
/// on any rank throws on every rank (Comm::agree) before anything is gathered.
RenderAcross render_across(const Comm& comm, const TileRenderer& tiles, int per_request, const ProgressFn& progress);

}  // namespace rp::dist
