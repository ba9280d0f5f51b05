// MpiComm: Comm over Open MPI's C API (any MPI-3 library), and make_comm() of a raypack built
// with MPI. raypack's traffic runs on its own duplicate of MPI_COMM_WORLD, whose error handler
// returns codes to check() instead of aborting inside the library.

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <new>
#include <vector>

#include "base/error.h"
#include "mpi/mpi_support.h"
#include "mpi/solo_comm.h"

// LeakSanitizer's interface when raypack is built with it (.ci/sanitize.sh); weak, so absent
// (null) in every other build.
extern "C" {
void __lsan_disable() __attribute__((weak));
void __lsan_enable() __attribute__((weak));
void __lsan_do_leak_check() __attribute__((weak));
}

namespace rp::dist {

namespace mpi {

namespace {

constexpr size_t kMaxMessage = size_t(1) << 30;  ///< bytes per message, within MPI's int counts

int rank_of(MPI_Comm comm) {
  int rank = -1;
  MPI_Comm_rank(comm, &rank);
  return rank;
}

std::string error_string(int rc) {
  char text[MPI_MAX_ERROR_STRING];
  int n = 0;
  if (MPI_Error_string(rc, text, &n) != MPI_SUCCESS) return cat("MPI error ", rc);
  return std::string(text, size_t(n));
}

}  // namespace

void abort_run(MPI_Comm comm, const std::string& message) {
  std::fprintf(stderr, "raypack: rank %d: %s\n", rank_of(comm), message.c_str());
  std::fflush(stderr);
  MPI_Abort(comm, 1);
  std::abort();  // MPI_Abort does not return
}

void check(MPI_Comm comm, int rc, const char* call) {
  if (rc != MPI_SUCCESS) abort_run(comm, cat(call, " failed: ", error_string(rc)));
}

void send_bytes(MPI_Comm comm, std::string_view bytes, int to) {
  do {
    const size_t n = std::min(bytes.size(), kMaxMessage);
    check(comm, MPI_Send(bytes.data(), int(n), MPI_BYTE, to, kTagBytes, comm), "MPI_Send");
    bytes.remove_prefix(n);
  } while (!bytes.empty());
}

void receive_bytes(MPI_Comm comm, std::string& out, size_t at, size_t n, int from) {
  do {
    const size_t m = std::min(n, kMaxMessage);
    check(comm, MPI_Recv(out.data() + at, int(m), MPI_BYTE, from, kTagBytes, comm, MPI_STATUS_IGNORE), "MPI_Recv");
    at += m;
    n -= m;
  } while (n > 0);
}

}  // namespace mpi

namespace {

class MpiComm final : public Comm {
 public:
  MpiComm(int& argc, char**& argv, DescribeFailure describe) : describe_(describe) {
    // Under LeakSanitizer: Open MPI keeps what MPI_Init allocates until (and past) MPI_Finalize,
    // some of it from plugins it opens and closes again within MPI_Init, whose leaks no stack
    // could name; what this thread allocates inside MPI_Init is not leak-checked.
    if (__lsan_disable) __lsan_disable();
    int provided = 0;
    const int init = MPI_Init_thread(&argc, &argv, MPI_THREAD_SERIALIZED, &provided);
    if (__lsan_enable) __lsan_enable();
    if (init != MPI_SUCCESS) throw Error("MPI_Init_thread failed");
    mpi::check(MPI_COMM_WORLD, MPI_Comm_dup(MPI_COMM_WORLD, &comm_), "MPI_Comm_dup");
    check(MPI_Comm_set_errhandler(comm_, MPI_ERRORS_RETURN), "MPI_Comm_set_errhandler");
    check(MPI_Comm_rank(comm_, &rank_), "MPI_Comm_rank");
    check(MPI_Comm_size(comm_, &size_), "MPI_Comm_size");
    // The tile hand-out's service thread calls MPI while the main thread renders; the two never
    // call at the same time.
    if (provided < MPI_THREAD_SERIALIZED)
      mpi::abort_run(comm_, "this MPI library does not provide MPI_THREAD_SERIALIZED, which raypack needs");
  }
  ~MpiComm() override {
    MPI_Comm_free(&comm_);
    // Under LeakSanitizer, the leak check now, while Open MPI's plugins are loaded: MPI_Finalize
    // unloads them, and a stack through an unloaded plugin names no library that
    // tests/mpi/openmpi-lsan.supp could match. The check at exit is then skipped.
    if (__lsan_do_leak_check) __lsan_do_leak_check();
    MPI_Finalize();
  }

  int rank() const override { return rank_; }
  int size() const override { return size_; }

  void agree(std::exception_ptr mine) const override {
    const int me = mine ? rank_ : size_;
    int lowest = size_;
    check(MPI_Allreduce(&me, &lowest, 1, MPI_INT, MPI_MIN, comm_), "MPI_Allreduce");
    if (lowest == size_) return;
    // The lowest failing rank describes its failure (a failure agreed before, inside nested
    // work, keeps its rank) and every rank throws it.
    std::string report;
    if (rank_ == lowest) {
      int origin = rank_;
      Failure f;
      try {
        std::rethrow_exception(mine);
      } catch (const RankFailure& agreed) {
        origin = agreed.rank();
        f = agreed.failure();
      } catch (...) {
        f = describe_(std::current_exception());
        if (rank_ != 0) f.message = cat("rank ", rank_, ": ", f.message);
      }
      report = cat(origin, ' ', f.status, ' ', f.message);
    }
    broadcast_from(report, lowest);
    const size_t a = report.find(' '), b = report.find(' ', a + 1);
    throw RankFailure(std::stoi(report.substr(0, a)),
                      Failure{std::stoi(report.substr(a + 1, b - a - 1)), report.substr(b + 1)});
  }

  void broadcast(std::string& bytes) const override { broadcast_from(bytes, 0); }

  void sum(std::span<uint64_t> values) const override {
    check(MPI_Allreduce(MPI_IN_PLACE, values.data(), int(values.size()), MPI_UINT64_T, MPI_SUM, comm_), "MPI_Allreduce");
  }

  uint64_t sum_before(uint64_t value) const override {
    uint64_t before = 0;
    check(MPI_Exscan(&value, &before, 1, MPI_UINT64_T, MPI_SUM, comm_), "MPI_Exscan");
    return rank_ == 0 ? 0 : before;  // MPI leaves rank 0's result undefined
  }

  std::string gather(std::string_view bytes, bool everywhere) const override {
    const uint64_t mine = bytes.size();
    std::vector<uint64_t> sizes(rank_ == 0 ? size_t(size_) : 0);
    check(MPI_Gather(&mine, 1, MPI_UINT64_T, sizes.data(), 1, MPI_UINT64_T, 0, comm_), "MPI_Gather");
    std::string all;
    if (rank_ == 0) {
      uint64_t total = 0;
      for (uint64_t s : sizes) total += s;
      all = allocate(total, "gathering");
      std::copy(bytes.begin(), bytes.end(), all.begin());
      size_t at = bytes.size();
      for (int r = 1; r < size_; ++r) {
        if (sizes[size_t(r)] > 0) mpi::receive_bytes(comm_, all, at, sizes[size_t(r)], r);
        at += sizes[size_t(r)];
      }
    } else if (!bytes.empty()) {
      mpi::send_bytes(comm_, bytes, 0);
    }
    if (everywhere) broadcast_from(all, 0);
    return all;
  }

  std::string scatter(std::span<const std::string> parts) const override {
    if (rank_ == 0) {
      RP_CHECK(parts.size() == size_t(size_), "scatter: ", parts.size(), " parts for ", size_, " ranks");
      for (int r = 1; r < size_; ++r) {
        const uint64_t n = parts[size_t(r)].size();
        check(MPI_Send(&n, 1, MPI_UINT64_T, r, mpi::kTagBytes, comm_), "MPI_Send");
        if (n > 0) mpi::send_bytes(comm_, parts[size_t(r)], r);
      }
      return parts[0];
    }
    uint64_t n = 0;
    check(MPI_Recv(&n, 1, MPI_UINT64_T, 0, mpi::kTagBytes, comm_, MPI_STATUS_IGNORE), "MPI_Recv");
    std::string part = allocate(n, "receiving");
    if (n > 0) mpi::receive_bytes(comm_, part, 0, n, 0);
    return part;
  }

  std::unique_ptr<TileSource> hand_out(const TileHandout& handout) const override {
    return mpi::hand_out_tiles(comm_, handout);
  }

 private:
  void check(int rc, const char* call) const { mpi::check(comm_, rc, call); }

  /// n bytes to receive into; running out of memory inside a collective call ends the job
  /// with one line (an exception would leave the other ranks waiting).
  std::string allocate(uint64_t n, const char* what) const {
    try {
      return std::string(size_t(n), '\0');
    } catch (const std::bad_alloc&) {
      mpi::abort_run(comm_, cat("out of memory while ", what, " ", n, " bytes from the other ranks"));
    }
  }

  void broadcast_from(std::string& bytes, int root) const {
    uint64_t n = bytes.size();
    check(MPI_Bcast(&n, 1, MPI_UINT64_T, root, comm_), "MPI_Bcast");
    if (rank_ != root) bytes = allocate(n, "receiving");
    for (size_t at = 0; at < n;) {
      const size_t m = std::min(size_t(n) - at, mpi::kMaxMessage);
      check(MPI_Bcast(bytes.data() + at, int(m), MPI_BYTE, root, comm_), "MPI_Bcast");
      at += m;
    }
  }

  DescribeFailure describe_;
  MPI_Comm comm_ = MPI_COMM_NULL;
  int rank_ = 0, size_ = 1;
};

}  // namespace

std::unique_ptr<Comm> make_comm(int& argc, char**& argv, DescribeFailure describe) {
  if (!launched_size()) return std::make_unique<SoloComm>();
  return std::make_unique<MpiComm>(argc, argv, describe);
}

}  // namespace rp::dist
