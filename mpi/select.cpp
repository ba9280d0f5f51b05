#include "mpi/select.h"

#include <array>
#include <bit>

#include "base/error.h"

namespace rp::dist {

namespace {

/// The bits of x as an integer in the order of the doubles: negative values' bits reversed,
/// the sign bit set on the others.
uint64_t key(double x) {
  const uint64_t bits = std::bit_cast<uint64_t>(x);
  return bits >> 63 ? ~bits : bits | (uint64_t(1) << 63);
}

double from_key(uint64_t k) { return std::bit_cast<double>(k >> 63 ? k & ~(uint64_t(1) << 63) : ~k); }

}  // namespace

double select_across(const Comm& comm, std::span<const double> values, uint64_t k) {
  uint64_t prefix = 0;  // the key's bits found so far, above `shift + 8`
  for (int shift = 56; shift >= 0; shift -= 8) {
    const uint64_t above = shift == 56 ? 0 : ~uint64_t(0) << (shift + 8);
    std::array<uint64_t, 256> count{};
    for (double v : values) {
      const uint64_t kv = key(v);
      if ((kv & above) == prefix) ++count[(kv >> shift) & 255];
    }
    comm.sum(count);
    size_t bucket = 0;
    while (bucket < 256 && k >= count[bucket]) k -= count[bucket++];
    RP_CHECK(bucket < 256, "select_across: k is beyond the values of every rank");
    prefix |= uint64_t(bucket) << shift;
  }
  return from_key(prefix);
}

}  // namespace rp::dist
