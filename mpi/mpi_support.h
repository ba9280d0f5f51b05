#pragma once
// What the MPI files of mpi/ share (mpi_comm.cpp, mpi_tiles.cpp): the rule for failed
// MPI calls and the byte transfers. The only header of raypack that includes <mpi.h>.

#include <mpi.h>

#include <memory>
#include <string>
#include <string_view>

#include "mpi/comm.h"

namespace rp::dist::mpi {

/// Message tags of raypack's point-to-point traffic (on its own communicator).
enum Tag : int { kTagBytes = 1, kTagTileRequest = 2, kTagTileReply = 3 };

/// Ends the job when an MPI call failed (rc not MPI_SUCCESS): one line on stderr naming this
/// rank, the call and MPI's reason, then MPI_Abort. A failed call leaves the communicator in
/// no state to agree on anything, so this is the one failure not reported through rank 0.
void check(MPI_Comm comm, int rc, const char* call);

/// Ends the job as check() does, with `message` as the reason (out of memory inside a
/// collective call, where an exception would leave the other ranks waiting).
[[noreturn]] void abort_run(MPI_Comm comm, const std::string& message);

/// Sends `bytes` to rank `to` in messages of at most 1 GiB (MPI counts are int); the receiver
/// must know the size.
void send_bytes(MPI_Comm comm, std::string_view bytes, int to);
/// Receives `n` bytes from rank `from` into out[at, at + n) (out must be large enough).
void receive_bytes(MPI_Comm comm, std::string& out, size_t at, size_t n, int from);

/// The tile source of this rank (see Comm::hand_out): on rank 0 a service thread answers the
/// other ranks' requests while its own threads take tiles directly.
std::unique_ptr<TileSource> hand_out_tiles(MPI_Comm comm, const TileHandout& handout);

}  // namespace rp::dist::mpi
