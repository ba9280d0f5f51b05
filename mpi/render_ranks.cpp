#include "mpi/render_ranks.h"

#include <tbb/parallel_for.h>

#include <array>
#include <chrono>
#include <cstring>
#include <mutex>
#include <numeric>
#include <utility>

#include "base/error.h"
#include "core/thread_limit.h"

namespace rp::dist {

namespace {

/// A rendered tile as it travels to rank 0: its number, then its pixels as floats.
constexpr size_t kTileRecord = sizeof(int32_t) + kTilePixels * 3 * sizeof(float);
static_assert(sizeof(Vec3f) == 3 * sizeof(float));

/// This rank's tiles (packed as kTileRecord records), its rays and what it did.
struct Part {
  std::string tiles;
  TileCounts counts;
  RankRender rank;
};

/// The order in which the hand-out's numbers visit the tiles: number k is tile k * stride mod
/// count, with stride coprime to count near count / golden ratio, so consecutive numbers land
/// far apart. Tiles differ in cost by region (a sky row against a row of mirrors); a range of
/// the hand-out then costs about the same as any other range of its size, as guided
/// self-scheduling assumes.
class Scattered {
 public:
  explicit Scattered(int count) : count_(count) {
    stride_ = std::max<int64_t>(1, int64_t(double(count) * 0.6180339887498949));
    while (std::gcd(stride_, int64_t(count)) != 1) ++stride_;
  }
  int operator()(int k) const { return int(int64_t(k) * stride_ % count_); }

 private:
  int64_t count_, stride_;
};

Part render_part(const Comm& comm, const TileRenderer& tiles, int per_request, const ProgressFn& progress) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  Part part;
  part.rank.threads = max_threads();
  const std::unique_ptr<TileSource> source = comm.hand_out({tiles.tile_count(), per_request});
  const Scattered order(tiles.tile_count());
  std::mutex mutex;
  try {
    tbb::parallel_for(
        0, part.rank.threads,
        [&](int) {
          std::array<Vec3f, kTilePixels> pixels;
          TileCounts counts;
          char record[kTileRecord];
          TileRenderer::Scratch scratch;
          for (int k; (k = source->next()) >= 0;) {
            const int t = order(k);
            try {
              tiles.render(t, pixels, counts, scratch);
            } catch (...) {
              source->cancel();  // this rank's other threads stop at their next tile, and the other ranks soon
              throw;
            }
            const int32_t index = t;
            std::memcpy(record, &index, sizeof index);
            std::memcpy(record + sizeof index, pixels.data(), sizeof pixels);
            {
              std::lock_guard lock(mutex);
              part.tiles.append(record, sizeof record);
              ++part.rank.tiles;
            }
            source->done();
            if (progress && comm.root()) progress(source->progress());
          }
          std::lock_guard lock(mutex);
          part.counts += counts;
        },
        tbb::simple_partitioner());
  } catch (...) {
    source->cancel();
    source->finish();
    throw;
  }
  part.rank.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  part.rank.handout = source->finish();
  return part;
}

}  // namespace

RenderAcross render_across(const Comm& comm, const TileRenderer& tiles, int per_request, const ProgressFn& progress) {
  RenderAcross out;
  together(comm, [&] {  // the image, before anything is rendered
    if (!comm.root()) return;
    out.image.width = tiles.settings().width;
    out.image.height = tiles.settings().height;
    out.image.rgb.assign(size_t(out.image.width) * size_t(out.image.height) * 3, 0.0f);
  });
  Part part = together(comm, [&] { return render_part(comm, tiles, per_request, progress); });
  uint64_t counts[] = {part.counts.primary, part.counts.shadow, part.counts.reflection, part.counts.refraction};
  comm.sum(counts);
  out.counts = {counts[0], counts[1], counts[2], counts[3]};
  out.ranks = gather_each(comm, part.rank);
  const std::string all = comm.gather(std::exchange(part.tiles, std::string()));
  together(comm, [&] {
    if (!comm.root()) return;
    RP_CHECK(all.size() == size_t(tiles.tile_count()) * kTileRecord, "render: ", all.size() / kTileRecord,
             " tiles gathered of ", tiles.tile_count());
    std::array<Vec3f, kTilePixels> pixels;
    for (size_t at = 0; at < all.size(); at += kTileRecord) {
      int32_t index;
      std::memcpy(&index, all.data() + at, sizeof index);
      std::memcpy(pixels.data(), all.data() + at + sizeof index, sizeof pixels);
      tiles.place(index, pixels, out.image);
    }
  });
  return out;
}

}  // namespace rp::dist
