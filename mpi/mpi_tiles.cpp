// The tiles of a render handed out over MPI ranks with dynamic load balancing. Rank 0 holds
// the next tile to hand out: its own threads take tiles from it one at a time, and a service
// thread answers the other ranks' requests with ranges of tiles, each a share of what is left
// (guided self-scheduling: Polychronopoulos and Kuck, "Guided Self-Scheduling", IEEE Trans.
// Computers 36(12), 1987), so ranges shrink towards the end and no rank is left with a long
// tail. A rank asks for its next range as soon as it receives one, so the reply travels while
// it renders the range it has; since it then holds two ranges, each is (tiles left) / (4 x
// ranks), and what a rank holds stays near guided self-scheduling's (tiles left) / (2 x ranks).

#include <atomic>
#include <chrono>
#include <mutex>
#include <thread>
#include <vector>

#include "mpi/mpi_support.h"

namespace rp::dist::mpi {

namespace {

/// A rank's request to rank 0: the tiles it has finished so far (for the progress rank 0
/// shows), and whether it stops the hand-out. 16 bytes.
struct Request {
  int64_t done = 0;
  int64_t cancel = 0;
};

/// Rank 0's reply: tiles [first, last), empty when none is left. 16 bytes.
struct Reply {
  int64_t first = 0, last = 0;
  bool empty() const { return first == last; }
};

/// How long rank 0's service thread sleeps when no request is waiting: the most a request
/// waits before rank 0 looks at it (hidden behind the range being rendered), for a poll that
/// costs next to nothing beside the render's threads.
constexpr auto kPoll = std::chrono::microseconds(100);

using Clock = std::chrono::steady_clock;

class RootTiles final : public TileSource {
 public:
  RootTiles(MPI_Comm comm, const TileHandout& h)
      : comm_(comm), count_(h.count), per_request_(h.per_request), remote_done_(size_t(size_of(comm))) {
    service_ = std::thread([this] { serve(); });
  }
  ~RootTiles() override {
    if (service_.joinable()) {
      cancel();
      service_.join();
    }
  }

  int next() override {
    if (cancelled_.load()) return -1;
    const int64_t t = next_.fetch_add(1);
    return t < count_ ? int(t) : -1;
  }
  void done() override { ++done_; }
  double progress() const override {
    int64_t done = done_.load();
    for (const std::atomic<int64_t>& d : remote_done_) done += d.load();
    return count_ ? double(done) / double(count_) : 1.0;
  }
  void cancel() override { cancelled_ = true; }
  HandoutStats finish() override {
    service_.join();
    return {};
  }

 private:
  static int size_of(MPI_Comm comm) {
    int n = 0;
    check(comm, MPI_Comm_size(comm, &n), "MPI_Comm_size");
    return n;
  }

  /// The next range for another rank: per_request_ tiles, or a share of what is left (see the
  /// top of this file).
  Reply take() {
    int64_t first = next_.load();
    for (;;) {
      if (cancelled_.load() || first >= count_) return {};
      const int64_t n =
          per_request_ > 0 ? per_request_ : std::max<int64_t>(1, (count_ - first) / (4 * int64_t(remote_done_.size())));
      const int64_t last = std::min<int64_t>(count_, first + n);
      if (next_.compare_exchange_weak(first, last)) return {first, last};
    }
  }

  /// Answers requests until every other rank has been told that no tile is left.
  void serve() {
    for (size_t open = remote_done_.size() - 1; open > 0;) {
      int waiting = 0;
      MPI_Status status;
      check(comm_, MPI_Iprobe(MPI_ANY_SOURCE, kTagTileRequest, comm_, &waiting, &status), "MPI_Iprobe");
      if (!waiting) {
        std::this_thread::sleep_for(kPoll);
        continue;
      }
      Request request;
      check(comm_, MPI_Recv(&request, sizeof request, MPI_BYTE, status.MPI_SOURCE, kTagTileRequest, comm_, MPI_STATUS_IGNORE),
            "MPI_Recv");
      remote_done_[size_t(status.MPI_SOURCE)] = request.done;
      if (request.cancel) cancelled_ = true;
      const Reply reply = take();
      check(comm_, MPI_Send(&reply, sizeof reply, MPI_BYTE, status.MPI_SOURCE, kTagTileReply, comm_), "MPI_Send");
      if (reply.empty()) --open;
    }
  }

  MPI_Comm comm_;
  int64_t count_;
  int per_request_;
  std::atomic<int64_t> next_{0}, done_{0};
  std::atomic<bool> cancelled_{false};
  std::vector<std::atomic<int64_t>> remote_done_;  ///< by rank: tiles each reported finished
  std::thread service_;
};

class RemoteTiles final : public TileSource {
 public:
  explicit RemoteTiles(MPI_Comm comm) : comm_(comm) { ask(false); }
  ~RemoteTiles() override { cancel(); }  // never leave a request in flight, nor rank 0 waiting

  int next() override {
    std::lock_guard lock(mutex_);
    if (first_ < last_) return int(first_++);
    if (over_) return -1;
    const auto start = Clock::now();
    const Reply reply = answer();
    stats_.wait_seconds += std::chrono::duration<double>(Clock::now() - start).count();
    if (reply.empty()) {
      over_ = true;
      return -1;
    }
    first_ = reply.first;
    last_ = reply.last;
    ask(false);
    return int(first_++);
  }
  void done() override { ++done_; }
  double progress() const override { return 0.0; }
  void cancel() override {
    std::lock_guard lock(mutex_);
    first_ = last_;
    if (over_) return;
    over_ = true;
    if (asked_ && answer().empty()) return;  // rank 0 has counted this rank out already
    ask(true);
    answer();
  }
  HandoutStats finish() override {
    std::lock_guard lock(mutex_);
    return stats_;
  }

 private:
  /// Sends a request; its reply is received by answer().
  void ask(bool cancel) {
    request_ = {done_.load(), cancel ? 1 : 0};
    check(comm_, MPI_Irecv(&reply_, sizeof reply_, MPI_BYTE, 0, kTagTileReply, comm_, &receive_), "MPI_Irecv");
    check(comm_, MPI_Isend(&request_, sizeof request_, MPI_BYTE, 0, kTagTileRequest, comm_, &send_), "MPI_Isend");
    asked_ = true;
    ++stats_.requests;
  }
  Reply answer() {
    check(comm_, MPI_Wait(&send_, MPI_STATUS_IGNORE), "MPI_Wait");
    check(comm_, MPI_Wait(&receive_, MPI_STATUS_IGNORE), "MPI_Wait");
    asked_ = false;
    return reply_;
  }

  MPI_Comm comm_;
  std::mutex mutex_;
  int64_t first_ = 0, last_ = 0;  ///< the range this rank's threads are taking tiles from
  bool asked_ = false;            ///< a request is out and its reply not yet received
  bool over_ = false;             ///< no tile is left for this rank
  Request request_;
  Reply reply_;
  MPI_Request send_ = MPI_REQUEST_NULL, receive_ = MPI_REQUEST_NULL;
  std::atomic<int64_t> done_{0};
  HandoutStats stats_;
};

}  // namespace

std::unique_ptr<TileSource> hand_out_tiles(MPI_Comm comm, const TileHandout& handout) {
  int rank = 0;
  check(comm, MPI_Comm_rank(comm, &rank), "MPI_Comm_rank");
  if (rank == 0) return std::make_unique<RootTiles>(comm, handout);
  return std::make_unique<RemoteTiles>(comm);
}

}  // namespace rp::dist::mpi
