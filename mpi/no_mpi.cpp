// make_comm() of a raypack built without MPI: one process, and a clear refusal when a launcher
// started several.

#include "base/error.h"
#include "mpi/comm.h"
#include "mpi/solo_comm.h"

namespace rp::dist {

std::unique_ptr<Comm> make_comm(int&, char**&, DescribeFailure) {
  if (const std::optional<int> n = launched_size(); n && *n != 1)
    throw Error(cat("an MPI launcher started this process", *n > 1 ? cat(" as one of ", *n) : std::string(),
                    ", but this raypack was built without MPI (install libopenmpi-dev, then configure and build "
                    "again: .ci/setup.sh)"));
  return std::make_unique<SoloComm>();
}

}  // namespace rp::dist
