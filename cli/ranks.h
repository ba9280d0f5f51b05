#pragma once
// What raypack's commands share for running across MPI ranks (mpi/comm.h): the rule
// that turns an exception into an exit status and one line, which main() and the agreement
// between ranks both follow, and the check that every rank runs the same command line.

#include <exception>

#include "mpi/comm.h"

namespace rp::cli {

/// The exit status and the one-line message (without "raypack: ") that main() reports for
/// `failure`: 2 for a UsageError, the agreed status of a dist::RankFailure, 1 for anything
/// else (out of memory named with the bytes asked for; exceptions from outside raypack as an
/// internal error).
dist::Failure describe_failure(std::exception_ptr failure);

/// Throws (on every rank) a UsageError led by the rank's number when a rank was started with
/// other arguments than rank 0 (argv[0], the program's path, may differ). Collective.
void check_same_command_line(const dist::Comm& comm, int argc, char** argv);

}  // namespace rp::cli
