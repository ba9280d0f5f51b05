// The distributed work of mpi/ over one process (SoloComm): the code that every rank of
// an MPI run executes gives what the one-process commands give. The runs across real MPI
// ranks are in tests/mpi/.

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "backends/registry.h"
#include "base/error.h"
#include "core/scene.h"
#include "mpi/diff_ranks.h"
#include "mpi/ray_parts.h"
#include "mpi/render_ranks.h"
#include "mpi/select.h"
#include "mpi/solo_comm.h"
#include "render/camera.h"
#include "tests/support/temp_dir.h"

namespace rp::dist {
namespace {

std::string file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(SelectAcross, FindsWhatNthElementFindsForEveryK) {
  const SoloComm comm;
  std::mt19937 rng(7);
  std::vector<double> values;
  // Ties, zeros, negatives, tiny and huge magnitudes, infinities.
  std::uniform_int_distribution<int> pick(0, 9);
  std::lognormal_distribution<double> spread(0.0, 20.0);
  for (int i = 0; i < 3000; ++i) {
    const int kind = pick(rng);
    values.push_back(kind == 0   ? 0.0
                     : kind == 1 ? 1.5
                     : kind == 2 ? -spread(rng)
                     : kind == 3 ? std::numeric_limits<double>::infinity()
                     : kind == 4 ? std::numeric_limits<double>::denorm_min() * double(i)
                                 : spread(rng));
  }
  std::vector<double> sorted = values;
  std::sort(sorted.begin(), sorted.end());
  for (uint64_t k = 0; k < values.size(); k += 7)
    ASSERT_EQ(std::bit_cast<uint64_t>(select_across(comm, values, k)), std::bit_cast<uint64_t>(sorted[k])) << k;
  EXPECT_EQ(select_across(comm, values, values.size() - 1), std::numeric_limits<double>::infinity());
  EXPECT_EQ(select_across(comm, std::vector<double>{-0.0, 2.0}, 0), -0.0);
  EXPECT_THROW(select_across(comm, values, values.size()), rp::Error);
}

TEST(Together, OneProcessRethrowsItsOwnException) {
  const SoloComm comm;
  EXPECT_EQ(together(comm, [] { return 42; }), 42);
  EXPECT_THROW(together(comm, [] { throw std::out_of_range("x"); }), std::out_of_range);
  EXPECT_THROW(together(comm, []() -> int { throw rp::Error("y"); }), rp::Error);
}

TEST(RenderAcross, OneProcessRendersTheImageAndRaysOfRender) {
  const SoloComm comm;
  const Scene scene = make_default_scene();
  const std::unique_ptr<Backend> backend = make_backend("embree", scene);
  for (const Sampler sampler : {Sampler::stratified, Sampler::adaptive}) {
    RenderSettings st;
    st.width = 45;
    st.height = 37;
    st.spp = 2;
    st.sampler = sampler;
    const Camera camera(*scene.camera(), st.width, st.height);
    const RenderResult want = render(scene, *backend, camera, st);
    const TileRenderer tiles(scene, *backend, camera, st);
    double last = 0;
    const RenderAcross got = render_across(comm, tiles, 0, [&](double f) { last = f; });
    EXPECT_EQ(got.image.width, st.width);
    EXPECT_EQ(got.image.height, st.height);
    ASSERT_EQ(got.image.rgb.size(), want.image.rgb.size());
    for (size_t i = 0; i < want.image.rgb.size(); ++i)
      ASSERT_EQ(std::bit_cast<uint32_t>(got.image.rgb[i]), std::bit_cast<uint32_t>(want.image.rgb[i])) << i;
    EXPECT_EQ(got.counts.primary, want.stats.primary);
    EXPECT_EQ(got.counts.shadow, want.stats.shadow);
    EXPECT_EQ(got.counts.reflection + got.counts.refraction, want.stats.reflection + want.stats.refraction);
    ASSERT_EQ(got.ranks.size(), 1u);
    EXPECT_EQ(got.ranks[0].tiles, uint64_t(tiles.tile_count()));
    EXPECT_EQ(last, 1.0);
  }
}

TEST(WriteHitsAcross, OneProcessWritesTheBytesOfWriteHits) {
  const SoloComm comm;
  test::TempDir tmp;
  std::vector<HitRecord> hits(1000);
  for (size_t i = 0; i < hits.size(); i += 3) hits[i] = {float(i) * 0.25f, uint32_t(i), 0.5f, 0.125f, {0, 1, 0}};
  for (const std::string name : {"a.hits", "a.csv"}) {
    write_hits(tmp / ("one-" + name), hits);
    write_hits_across(comm, tmp / name, hits);
    EXPECT_EQ(file_bytes(tmp / name), file_bytes(tmp / ("one-" + name))) << name;
  }
  EXPECT_EQ(tmp.entries().size(), 4u) << "a temporary was left";
}

TEST(CombineAcross, OneProcessKeepsTheDiff) {
  const SoloComm comm;
  const Scene scene = make_default_scene();
  const RaySet set = random_rays(scene, 2000, 3);
  const std::unique_ptr<Backend> a = make_backend("embree", scene);
  std::vector<Hit> ha(set.rays.size()), hb(set.rays.size());
  a->intersect(set.rays, ha, Coherence::incoherent);
  std::vector<ReferenceHit> ref(set.rays.size());
  Reference(scene).intersect(set.rays, ref);
  for (size_t i = 0; i < hb.size(); ++i) hb[i] = i % 5 ? ha[i] : Hit{};  // B misses every fifth ray
  const DiffResult d = diff_hits(scene, set.rays, ha, hb, ref, {});
  const DiffResult c = combine_across(comm, d);
  EXPECT_EQ(to_json(c, "s", "r", "a", "b", {}), to_json(d, "s", "r", "a", "b", {}));
  EXPECT_GT(d.count[size_t(DiffClass::hit_miss)], 0u);
  // The reference's hits of the same rays, as diff's diffuse rays start from them.
  const std::vector<Hit> rh = reference_hits_across(comm, scene, set.rays);
  ASSERT_EQ(rh.size(), ref.size());
  for (size_t i = 0; i < rh.size(); ++i) {
    EXPECT_EQ(rh[i].prim_id, ref[i].prim_id) << i;
    if (ref[i].hit()) {
      EXPECT_EQ(rh[i].t, float(ref[i].t)) << i;
    }
  }
}

}  // namespace
}  // namespace rp::dist
