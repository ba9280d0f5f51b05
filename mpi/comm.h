#pragma once
/// The processes of one raypack run: a single process, or the ranks of an MPI job started by
/// mpirun (Open MPI, MPICH) or srun. The commands that run across ranks (render, trace, diff)
/// reach the other ranks only through Comm, whose factory make_comm() is the seam: SoloComm
/// (solo_comm.cpp) for one process, MpiComm (mpi_comm.cpp, over Open MPI's C API) when this
/// raypack was built with MPI (CMake found it) and a launcher started it. A build without MPI
/// has no MpiComm and behaves as one process.
///
/// Collective calls must be made by every rank, in the same order. Failures follow one rule:
/// work that can fail on one rank runs inside together(), whose agreement turns a failure on
/// any rank into the same exception on every rank, so no rank is left waiting in a collective
/// call for one that gave up.

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <exception>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace rp::dist {

/// A failure as raypack reports it: the exit status (1: failed while running, 2: a bad flag
/// or value) and the one-line message, without the "raypack: " that main() puts before it.
struct Failure {
  int status = 1;
  std::string message;
};

/// How main() turns an exception into what it reports; make_comm() keeps it so that a failure
/// on one rank can be reported by rank 0.
using DescribeFailure = Failure (*)(std::exception_ptr failure);

/// Thrown on every rank by Comm::agree() when some rank failed: the failure of the lowest
/// failing rank, its message led by "rank N: " when N is not 0.
class RankFailure : public std::exception {
 public:
  RankFailure(int rank, Failure failure) : rank_(rank), failure_(std::move(failure)) {}
  int rank() const { return rank_; }
  const Failure& failure() const { return failure_; }
  const char* what() const noexcept override { return failure_.message.c_str(); }

 private:
  int rank_;
  Failure failure_;
};

/// How a render's tiles are handed out over the ranks.
struct TileHandout {
  int count = 0;        ///< tiles 0 .. count-1
  int per_request = 0;  ///< tiles rank 0 hands another rank per request; 0: a share of what is left (guided)
};

/// What handing out tiles cost one rank.
struct HandoutStats {
  uint64_t requests = 0;    ///< requests sent to rank 0 (0 on rank 0, whose threads take tiles directly)
  double wait_seconds = 0;  ///< time this rank's threads waited for rank 0's replies, summed
};

/// The tiles of one render as one rank receives them. Tiles come one at a time to any of the
/// rank's threads; every tile goes to exactly one rank.
class TileSource {
 public:
  virtual ~TileSource() = default;
  /// The next tile for this rank to render, or -1 once there is none left (then always -1).
  /// Thread-safe; may wait for rank 0's reply to a request.
  virtual int next() = 0;
  /// Records that this rank finished a tile (for the progress rank 0 shows). Thread-safe.
  virtual void done() = 0;
  /// Fraction of all tiles finished, as far as this rank knows: on rank 0 its own tiles and
  /// what the other ranks reported with their last requests. Thread-safe.
  virtual double progress() const = 0;
  /// Stops the hand-out after a failure on this rank: next() returns -1 from now on here and,
  /// at their next request, on every other rank.
  virtual void cancel() = 0;
  /// Ends the hand-out on this rank, once next() has returned -1 or cancel() was called (rank
  /// 0 waits until every rank has been told that no tile is left). Collective.
  virtual HandoutStats finish() = 0;
};

class Comm {
 public:
  virtual ~Comm() = default;
  virtual int rank() const = 0;  ///< in [0, size())
  virtual int size() const = 0;
  bool root() const { return rank() == 0; }

  /// Collective. `mine`: this rank's failure, or null. Returns when no rank failed; otherwise
  /// throws on every rank: one process rethrows its own exception; across ranks every rank
  /// throws RankFailure with the lowest failing rank's failure.
  virtual void agree(std::exception_ptr mine) const = 0;
  /// Collective: rank 0's `bytes` on every rank.
  virtual void broadcast(std::string& bytes) const = 0;
  /// Collective: each value replaced by its sum over the ranks, on every rank.
  virtual void sum(std::span<uint64_t> values) const = 0;
  /// Collective: the sum of `value` over the ranks before this one (0 on rank 0).
  virtual uint64_t sum_before(uint64_t value) const = 0;
  /// Collective: every rank's `bytes`, concatenated in rank order, on rank 0 (`everywhere`: on
  /// every rank); an empty string on the other ranks.
  virtual std::string gather(std::string_view bytes, bool everywhere = false) const = 0;
  /// Collective: rank 0's parts[r] on rank r (`parts` has size() entries on rank 0, and is not
  /// read elsewhere).
  virtual std::string scatter(std::span<const std::string> parts) const = 0;
  /// Collective: this rank's source of the tiles of one render.
  virtual std::unique_ptr<TileSource> hand_out(const TileHandout& handout) const = 0;
};

/// The processes of this run: MpiComm when an MPI launcher started this process and raypack
/// was built with MPI (MPI is initialised here, finalised by the Comm's destructor), else
/// SoloComm. Throws rp::Error when a launcher started several processes and this raypack
/// has no MPI. `describe` reports a rank's failure to the others (see agree()).
std::unique_ptr<Comm> make_comm(int& argc, char**& argv, DescribeFailure describe);

/// What the environment says about an MPI launcher that started this process: the number of
/// processes it started (0 when it does not say), or nothing when no launcher did. Read from
/// the variables the launchers set: OMPI_COMM_WORLD_SIZE (Open MPI), PMI_SIZE (MPICH's
/// Hydra, srun with PMI-2), PMIX_RANK (srun or prte with PMIx).
std::optional<int> launched_size();

/// Runs f() on every rank and agrees on the outcome (Comm::agree): when f throws on any rank,
/// every rank throws. A collective call inside f must be made by every rank whatever happens
/// to f on it (a rank that failed before the call would leave the others waiting in it), so f
/// is this rank's own work, or work that ends its collective part on failure too (the tile
/// hand-out's cancel). With one process this is f() itself.
template <typename F>
auto together(const Comm& comm, F&& f) -> decltype(f()) {
  using R = decltype(f());
  std::exception_ptr failure;
  if constexpr (std::is_void_v<R>) {
    try {
      f();
    } catch (...) {
      failure = std::current_exception();
    }
    comm.agree(failure);
  } else {
    std::optional<R> result;
    try {
      result.emplace(f());
    } catch (...) {
      failure = std::current_exception();
    }
    comm.agree(failure);
    return std::move(*result);
  }
}

/// Collective: the `values` of every rank (trivially copyable), concatenated in rank order, on
/// rank 0 (`everywhere`: on every rank); empty elsewhere.
template <typename T>
std::vector<T> gather_vector(const Comm& comm, std::span<const T> values, bool everywhere = false) {
  static_assert(std::is_trivially_copyable_v<T>);
  const std::string bytes =
      comm.gather({reinterpret_cast<const char*>(values.data()), values.size_bytes()}, everywhere);
  std::vector<T> out(bytes.size() / sizeof(T));
  if (!out.empty()) std::memcpy(out.data(), bytes.data(), bytes.size());
  return out;
}

/// Collective: every rank's `value` (a trivially copyable struct), in rank order, on rank 0;
/// empty elsewhere.
template <typename T>
std::vector<T> gather_each(const Comm& comm, const T& value) {
  return gather_vector(comm, std::span<const T>(&value, 1));
}

}  // namespace rp::dist
