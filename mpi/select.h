#pragma once
/// Order statistics over the values of every rank without gathering them.

#include <cstdint>
#include <span>

#include "mpi/comm.h"

namespace rp::dist {

/// The k-th smallest (from 0) of the values of all ranks together, k below their total count:
/// exactly the value std::nth_element finds in the union (NaNs ordered after +inf, -0 before
/// +0). A radix select over the values' order-preserving 64-bit keys, 8 bits a round: 8
/// rounds, each a pass over this rank's values and one sum of 256 counts over the ranks.
/// Collective.
double select_across(const Comm& comm, std::span<const double> values, uint64_t k);

}  // namespace rp::dist
