// The simd backend's 8-wide BVH and kernels: structure invariants, determinism across thread
// counts, and the 8-wide kernels against the scalar routines of core/geometry.
// Built for AVX2+FMA with -ffp-contract=off (CMake links rp::avx2 and rp::fp_strict).

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <bit>
#include <cstring>
#include <functional>
#include <random>
#include <set>

#include "backends/registry.h"
#include "backends/simd/bvh8.h"
#include "backends/simd/moller_trumbore.h"
#include "backends/simd/packet.h"
#include "core/geometry/slab.h"
#include "core/geometry/triangle.h"
#include "tests/backends/kernel_support.h"
#include "tests/support/scenes.h"

namespace rp::bvh8 {
namespace {

/// prim_ids of a leaf.
std::vector<uint32_t> leaf_prims(const Bvh8& t, int32_t ref) {
  std::vector<uint32_t> ids;
  for (uint32_t i = 0; i < t.leaf(ref).n; ++i) ids.push_back(t.prim_id(ref, i));
  return ids;
}

/// Every leaf reference of the tree.
std::vector<int32_t> leaves(const Bvh8& t) {
  std::vector<int32_t> out;
  for (const Bvh8Node& n : t.nodes)
    for (int c = 0; c < 8 && n.child[c] != kEmpty; ++c)
      if (is_leaf(n.child[c])) out.push_back(n.child[c]);
  return out;
}

TEST(Bvh8Build, EveryPrimitiveInExactlyOneLeaf) {
  for (SplitRule rule : {SplitRule::sah, SplitRule::median}) {
    const Scene sc = test::mixed_soup(1, 3000, true);
    const Bvh8 t = build(sc, {rule, 8});
    std::multiset<uint32_t> seen;
    const std::vector<int32_t> refs = leaves(t);
    EXPECT_EQ(refs.size(), size_t(t.stats.leaves));
    for (int32_t ref : refs)
      for (uint32_t id : leaf_prims(t, ref)) seen.insert(id);
    size_t degenerate = 0;
    for (uint32_t id = 0; id < sc.prim_count() - sc.planes().size(); ++id) {
      const PrimLocation r = sc.locate(id);
      bool zero_area = false;
      if (r.kind == PrimKind::triangle) {
        const MeshView& m = sc.meshes()[r.shape];
        const Vec3f n = cross(m.vertex(r.local, 1) - m.vertex(r.local, 0), m.vertex(r.local, 2) - m.vertex(r.local, 0));
        zero_area = n.x == 0 && n.y == 0 && n.z == 0;
      }
      degenerate += zero_area;
      EXPECT_EQ(seen.count(id), zero_area ? 0u : 1u) << "prim " << id;
    }
    EXPECT_EQ(degenerate, 60u);
    EXPECT_EQ(seen.size(), size_t(t.stats.prims));
    // An analytic primitive has a leaf of its own, so its own box culls rays before its test.
    for (int32_t ref : refs) {
      const std::vector<uint32_t> ids = leaf_prims(t, ref);
      const bool analytic = std::any_of(ids.begin(), ids.end(), [&](uint32_t id) { return id >= sc.sphere_base(); });
      if (analytic) {
        EXPECT_EQ(ids.size(), 1u);
      }
    }
    // Every leaf holds its triangles' corners bit for bit (an analytic primitive's are NaN),
    // and the leaves lie back to back: their words tile the array up to its padding.
    std::vector<std::pair<size_t, size_t>> ranges;
    for (int32_t ref : refs) {
      EXPECT_LE(t.leaf(ref).n, 8u);
      const Leaf leaf = t.leaf(ref);
      ranges.emplace_back(size_t(leaf.words - t.leaf_data.data()), leaf_words(leaf.n, leaf.v));
      for (uint32_t k = 0; k < leaf.n; ++k) {
        const PrimLocation at = sc.locate(leaf.prim(k));
        for (uint32_t j = 0; j < 3; ++j) {
          const Vec3f got = leaf.vertex(k, j);
          if (at.kind != PrimKind::triangle) {
            EXPECT_TRUE(std::isnan(got.x) && std::isnan(got.y) && std::isnan(got.z));
            continue;
          }
          const Vec3f want = sc.meshes()[at.shape].vertex(at.local, j);
          EXPECT_EQ(0, std::memcmp(&got, &want, sizeof(Vec3f))) << "prim " << leaf.prim(k) << " corner " << j;
        }
      }
    }
    std::sort(ranges.begin(), ranges.end());
    size_t next = 0;
    for (const auto& [first, words] : ranges) {
      EXPECT_EQ(first, next);
      next = first + words;
    }
    EXPECT_EQ(t.leaf_data.size(), next + kLeafPad);
  }
}

TEST(Bvh8Build, ChildBoxesContainEverythingBelowThem) {
  const Scene sc = test::mixed_soup(2, 2000, false);
  const Bvh8 t = build(sc, {});
  std::function<Box3f(int32_t)> bounds_below = [&](int32_t ref) {
    Box3f b;
    if (is_leaf(ref)) {
      for (uint32_t id : leaf_prims(t, ref)) {
        const PrimLocation r = sc.locate(id);
        if (r.kind == PrimKind::triangle)
          for (int k = 0; k < 3; ++k) b.extend(sc.meshes()[r.shape].vertex(r.local, k));
        else
          b.extend(sc.prim_bounds(id));
      }
      return b;
    }
    const Bvh8Node& n = t.nodes[size_t(ref)];
    for (int c = 0; c < 8 && n.child[c] != kEmpty; ++c) {
      const Box3f child({n.lo_x[c], n.lo_y[c], n.lo_z[c]}, {n.hi_x[c], n.hi_y[c], n.hi_z[c]});
      const Box3f below = bounds_below(n.child[c]);
      EXPECT_TRUE(child.contains(below.lo) && child.contains(below.hi)) << "node " << ref << " child " << c;
      EXPECT_EQ(child, below) << "child boxes are tight";
      b.extend(child);
    }
    return b;
  };
  const Box3f all = bounds_below(0);
  EXPECT_EQ(all, t.bounds);
  EXPECT_GT(t.stats.nodes, 1u);
  EXPECT_GT(t.stats.depth, 1u);
  EXPECT_GT(t.stats.sah_cost, 1.0);
  EXPECT_EQ(t.stats.bytes, t.nodes.size() * sizeof(Bvh8Node) + t.leaf_data.size() * sizeof(float));
}

TEST(Bvh8Build, SameTreeForOneAndTwoThreads) {
  const Scene soup = test::mixed_soup(3, 60000, false);  // large enough for the parallel recursion
  const Scene slivers = test::sliver_soup(3, 20000);
  for (const bool spatial : {false, true}) {
    const Scene& sc = spatial ? slivers : soup;
    auto run = [&](int threads) {
      tbb::global_control c(tbb::global_control::max_allowed_parallelism, size_t(threads));
      return build(sc, {.spatial_splits = spatial});
    };
    const Bvh8 a = run(1), b = run(2);
    ASSERT_EQ(a.nodes.size(), b.nodes.size()) << "spatial " << spatial;
    ASSERT_EQ(a.leaf_data.size(), b.leaf_data.size());
    EXPECT_EQ(0, std::memcmp(a.nodes.data(), b.nodes.data(), a.nodes.size() * sizeof(Bvh8Node)));
    EXPECT_EQ(0, std::memcmp(a.leaf_data.data(), b.leaf_data.data(), a.leaf_data.size() * sizeof(float)));
  }
}

/// Spatial splits put a triangle in several leaves, each with a box around only its part
/// there: every point of every triangle lies in the box of some leaf that holds it, child
/// boxes nest, no leaf holds a primitive twice, and splits did happen (some triangle is in
/// more than one leaf) with fewer box-area-weighted tests than without them.
TEST(Bvh8Build, SpatialSplitsCoverEveryTriangle) {
  const Scene sc = test::sliver_soup(7, 3000);
  const Bvh8 t = build(sc, {.spatial_splits = true});
  std::vector<std::vector<Box3f>> boxes(sc.sphere_base() + 1);  // per primitive: its leaves' boxes
  std::function<void(int32_t, const Box3f&)> walk = [&](int32_t ref, const Box3f& box) {
    if (is_leaf(ref)) {
      const std::vector<uint32_t> ids = leaf_prims(t, ref);
      EXPECT_LE(ids.size(), 8u);
      EXPECT_EQ(std::set<uint32_t>(ids.begin(), ids.end()).size(), ids.size()) << "a primitive twice in a leaf";
      for (uint32_t id : ids) boxes.at(id).push_back(box);
      return;
    }
    const Bvh8Node& n = t.nodes[size_t(ref)];
    for (int c = 0; c < 8 && n.child[c] != kEmpty; ++c) {
      const Box3f child({n.lo_x[c], n.lo_y[c], n.lo_z[c]}, {n.hi_x[c], n.hi_y[c], n.hi_z[c]});
      EXPECT_TRUE(box.contains(child.lo) && box.contains(child.hi)) << "node " << ref << " child " << c;
      walk(n.child[c], child);
    }
  };
  walk(0, t.bounds);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  size_t split = 0;
  for (uint32_t id = 0; id < sc.triangle_count(); ++id) {
    ASSERT_FALSE(boxes[id].empty()) << "prim " << id << " in no leaf";
    split += boxes[id].size() > 1;
    const MeshView& m = sc.meshes()[0];
    const Vec3f a = m.vertex(id, 0), b = m.vertex(id, 1), c = m.vertex(id, 2);
    for (int k = 0; k < 32; ++k) {
      float s = u(rng), r = u(rng);
      if (s + r > 1.0f) s = 1.0f - s, r = 1.0f - r;
      const Vec3f p = k < 3 ? m.vertex(id, uint32_t(k)) : a + (b - a) * s + (c - a) * r;
      EXPECT_TRUE(std::any_of(boxes[id].begin(), boxes[id].end(), [&](const Box3f& x) { return x.contains(p); }))
          << "prim " << id << " point " << k << " in none of its " << boxes[id].size() << " leaves";
    }
  }
  EXPECT_EQ(boxes[sc.sphere_base()].size(), 1u) << "an analytic primitive is never split";
  EXPECT_GT(split, 100u);
  EXPECT_LT(t.stats.sah_cost, build(sc, {}).stats.sah_cost);
}

/// The collapse minimises the SAH cost, so no node keeps a child node whose children it has
/// room for: lifting them into the parent would remove that child's traversal cost (its
/// area) and change nothing else. Also checks that child counts add up.
TEST(Bvh8Build, NoNodeCouldAbsorbAChildNode) {
  for (SplitRule rule : {SplitRule::sah, SplitRule::median}) {
    const Scene sc = test::mixed_soup(5, 20000, false);
    const Bvh8 t = build(sc, {rule, 8});
    auto width = [&](const Bvh8Node& n) {
      int k = 0;
      while (k < 8 && n.child[k] != kEmpty) ++k;
      return k;
    };
    size_t children = 0;
    for (size_t i = 0; i < t.nodes.size(); ++i) {
      const Bvh8Node& n = t.nodes[i];
      const int k = width(n);
      EXPECT_GE(k, i == 0 ? 1 : 2) << "node " << i;
      children += size_t(k);
      for (int c = 0; c < k; ++c) {
        if (is_leaf(n.child[c])) continue;
        const Box3f box({n.lo_x[c], n.lo_y[c], n.lo_z[c]}, {n.hi_x[c], n.hi_y[c], n.hi_z[c]});
        if (!(box.area() > 0.0f)) continue;
        EXPECT_GT(k - 1 + width(t.nodes[size_t(n.child[c])]), 8) << "node " << i << " could absorb child " << c;
      }
    }
    EXPECT_EQ(children, t.nodes.size() - 1 + t.stats.leaves);  // every node but the root is a child once
  }
}

/// The lecture notes' rule: longest axis, centroid median, balanced. Halving n until it fits a leaf
/// of 4 leaves every leaf with 2..4 primitives (5 splits into 2 + 3); SAH has no such floor.
/// Triangles only: an analytic primitive takes a leaf of its own.
TEST(Bvh8Build, MedianRuleGivesBalancedLeaves) {
  Scene sc;
  sc.add_mesh(to_triangle_mesh(test::mixed_soup(4, 5000, false).meshes()[0]));
  const Bvh8 t = build(sc, {SplitRule::median, 4});
  uint32_t lo = 99, hi = 0;
  for (int32_t ref : leaves(t)) {
    lo = std::min(lo, t.leaf(ref).n);
    hi = std::max(hi, t.leaf(ref).n);
  }
  EXPECT_LE(hi, 4u);
  EXPECT_GE(lo, 2u);
}

/// The rule sorts by the triangles' centres of mass, not by their boxes' centres: on x, P's
/// centre of mass (1.0) lies left of Q's (1.3) and R's (1.4), its box centre (1.5) right of
/// them, so the median of four splits {P, Q} from {R, S}, where box centres would give
/// {Q, R} and {P, S}.
TEST(Bvh8Build, MedianRuleSortsByCentreOfMass) {
  TriangleMesh m;
  m.positions = {{0, 0, 0},    {0, 0.1f, 0},   {3, 0, 0},       // P
                 {1.25f, 0, 0}, {1.35f, 0, 0}, {1.3f, 0.1f, 0},  // Q
                 {1.35f, 0, 0}, {1.45f, 0, 0}, {1.4f, 0.1f, 0},  // R
                 {4.9f, 0, 0},  {5.1f, 0, 0},  {5, 0.1f, 0}};    // S
  m.indices = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
  Scene sc;
  sc.add_mesh(m);
  const Bvh8 t = build(sc, {SplitRule::median, 2});
  std::set<std::vector<uint32_t>> got;
  for (int32_t ref : leaves(t)) {
    std::vector<uint32_t> ids = leaf_prims(t, ref);
    std::sort(ids.begin(), ids.end());
    got.insert(ids);
  }
  EXPECT_EQ(got, (std::set<std::vector<uint32_t>>{{0, 1}, {2, 3}}));
}

/// Copies of one triangle cannot be separated by any plane: each spatial split would send
/// all of them to both sides. The split budget bounds the tree at twice as many leaf entries
/// as primitives, and the build ends.
TEST(Bvh8Build, SpatialSplitsStayWithinTheirBudget) {
  TriangleMesh m;
  m.positions = {{-1.0f, -1.0f, -1.0f}, {1.0f, 1.0f, 1.0f}, {1.0f, 1.0f, 0.98f}};
  for (uint32_t i = 0; i < 3000; ++i) m.indices.insert(m.indices.end(), {0, 1, 2});
  Scene sc = test::sliver_soup(5, 500);
  sc.add_mesh(std::move(m));
  const Bvh8 t = build(sc, {.spatial_splits = true});
  size_t entries = 0;
  std::set<uint32_t> prims;
  for (int32_t ref : leaves(t))
    for (uint32_t id : leaf_prims(t, ref)) {
      ++entries;
      prims.insert(id);
    }
  EXPECT_EQ(prims.size(), size_t(t.stats.prims));
  EXPECT_LE(entries, 2 * size_t(t.stats.prims));
  EXPECT_GT(entries, size_t(t.stats.prims)) << "some triangle was split";
}

/// The closest hit is the least (t, prim_id) whatever the tree, and a triangle is tested by
/// the same routine in every leaf that holds it: spatial splits change no hit's bits and no
/// occlusion answer, on single rays and packets.
TEST(Bvh8Build, SpatialSplitsChangeNoHit) {
  const Scene sc = test::sliver_soup(9, 4000);
  const auto plain = make_backend("simd", sc);
  const auto spatial = make_backend("simd", sc, {.variant = "spatial", .device_config = {}, .coherent_method = {}, .incoherent_method = {}});
  std::vector<Ray> rays = test::random_rays(21, 16000);
  const std::vector<Ray> axis = test::axis_rays();
  rays.insert(rays.end(), axis.begin(), axis.end());
  size_t hits = 0;
  for (const Coherence coh : {Coherence::incoherent, Coherence::coherent}) {
    std::vector<Hit> a(rays.size()), b(rays.size());
    std::vector<uint8_t> oa(rays.size()), ob(rays.size());
    plain->intersect(rays, a, coh);
    spatial->intersect(rays, b, coh);
    plain->occluded(rays, oa, coh);
    spatial->occluded(rays, ob, coh);
    for (size_t i = 0; i < rays.size(); ++i) {
      EXPECT_EQ(0, std::memcmp(&a[i], &b[i], sizeof(Hit)))
          << "ray " << i << ": prim " << a[i].prim_id << " / " << b[i].prim_id;
      EXPECT_EQ(oa[i], ob[i]) << "ray " << i;
      hits += a[i].hit();
    }
  }
  EXPECT_GT(hits, rays.size() / 2);
}

TEST(Bvh8Build, EmptySceneHasNoNodes) {
  const Bvh8 t = build(Scene{}, {});
  EXPECT_TRUE(t.empty());
  EXPECT_EQ(t.stats.bytes, 0u);
}

/// Both traversals return exactly the closest float Möller–Trumbore hit over all triangles,
/// and that triangle: large overlapping triangles put hits of several leaves in one shared
/// block and make traversal order matter.
TEST(Bvh8Traversal, ClosestHitEqualsBruteForceOverEveryTriangle) {
  std::mt19937 rng(8);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  TriangleMesh m;
  m.name = "overlap";
  for (int i = 0; i < 600; ++i) {
    const Vec3f c{u(rng), u(rng), u(rng)};
    for (int k = 0; k < 3; ++k) m.positions.push_back(c + Vec3f{u(rng), u(rng), u(rng)} * 0.6f);
    const uint32_t b = uint32_t(m.positions.size() - 3);
    m.indices.insert(m.indices.end(), {b, b + 1, b + 2});
  }
  Scene sc;
  sc.add_mesh(m);
  const auto backend = make_backend("simd", sc);
  std::vector<Ray> rays;
  for (int i = 0; i < 20000; ++i) {
    const Vec3f o{u(rng) * 2.0f, u(rng) * 2.0f, u(rng) * 2.0f};
    rays.push_back({o, 0.0f, Vec3f{u(rng), u(rng), u(rng)} * 0.5f - o, std::numeric_limits<float>::infinity()});
  }
  for (Coherence coh : {Coherence::incoherent, Coherence::coherent}) {
    std::vector<Hit> hits(rays.size());
    backend->intersect(rays, hits, coh);
    size_t hit_count = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
      float best = std::numeric_limits<float>::infinity();
      for (uint32_t t = 0; t < m.triangle_count(); ++t) {
        const Intersection<float> h = intersect_triangle_mt_normal(rays[i], m.vertex(t, 0), m.vertex(t, 1), m.vertex(t, 2));
        if (h.hit) best = std::min(best, h.t);
      }
      hit_count += std::isfinite(best);
      ASSERT_EQ(hits[i].t, best) << "ray " << i << (coh == Coherence::coherent ? " (packets)" : " (single)");
      if (hits[i].hit()) {
        const MeshView& mm = sc.meshes()[0];
        const uint32_t t = hits[i].prim_id;
        ASSERT_LT(t, mm.triangle_count());
        EXPECT_EQ(intersect_triangle_mt_normal(rays[i], mm.vertex(t, 0), mm.vertex(t, 1), mm.vertex(t, 2)).t, best);
      }
    }
    EXPECT_GT(hit_count, rays.size() / 2);
  }
}

/// A leaf gives back each corner's floats bit for bit, stores each distinct vertex once
/// (corners with the same bits merged, -0 and +0 kept apart), and its 8-wide view holds the
/// corners in lanes 0..n-1 and NaN past them (see LeafView), for leaves of 1..8 with 1..24 vertices.
TEST(Bvh8, LeafStoresEachDistinctVertexOnceAndGivesBackEveryCorner) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-2.0f, 2.0f);
  for (int iter = 0; iter < 2000; ++iter) {
    const uint32_t n = 1 + uint32_t(iter) % 8;
    std::vector<Vec3f> pool;  // corners drawn from a pool of 1..24 points
    const size_t pool_size = 1 + size_t(iter) % 24;
    for (size_t i = 0; i < pool_size; ++i) pool.push_back({u(rng), u(rng), u(rng)});
    if (pool_size > 1) pool[1] = {-0.0f, pool[0].y, pool[0].z}, pool[0].x = 0.0f;  // differ in a sign bit only
    Vec3f c[3][8];
    std::vector<Vec3f> used;
    for (uint32_t k = 0; k < n; ++k)
      for (int j = 0; j < 3; ++j) {
        c[j][k] = pool[size_t(rng()) % pool_size];
        if (std::none_of(used.begin(), used.end(), [&](const Vec3f& p) { return std::memcmp(&p, &c[j][k], 12) == 0; }))
          used.push_back(c[j][k]);
      }
    const std::vector<float> words = make_leaf(c[0], c[1], c[2], n);
    const Leaf leaf(words.data());
    ASSERT_EQ(leaf.v, used.size());
    const LeafView lv(leaf);
    const Vec3x8* view[3] = {&lv.v0, &lv.v1, &lv.v2};
    for (uint32_t k = 0; k < 8; ++k)
      for (uint32_t j = 0; j < 3; ++j) {
        const Vec3f lane = view[j]->lane(int(k));
        if (k >= n) {  // v0 NaN and v1's x: enough for both tests to see only NaN there
          if (j == 0) {
            EXPECT_TRUE(std::isnan(lane.x) && std::isnan(lane.y) && std::isnan(lane.z)) << "lane " << k << " of " << n;
          } else if (j == 1) {
            EXPECT_TRUE(std::isnan(lane.x)) << "lane " << k << " of " << n;
          }
          continue;
        }
        EXPECT_EQ(leaf.prim(k), k);
        const Vec3f stored = leaf.vertex(k, j);
        EXPECT_EQ(0, std::memcmp(&stored, &c[j][k], 12)) << "iter " << iter << " corner " << j << " of " << k;
        EXPECT_EQ(0, std::memcmp(&lane, &c[j][k], 12)) << "iter " << iter << " lane " << k << " corner " << j;
      }
  }
}

/// Möller–Trumbore ×8 reproduces rp::intersect_triangle_mt_normal bit for bit, both ways of
/// use, on leaves of 1..8 primitives; the lanes past a leaf never hit.
TEST(Kernels, MollerTrumbore8MatchesScalarBitForBit) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-2.0f, 2.0f);
  auto v3 = [&] { return Vec3f{u(rng), u(rng), u(rng)}; };
  int hits = 0;
  for (int iter = 0; iter < 8000; ++iter) {
    const uint32_t n = 1 + uint32_t(iter) % 8;
    Vec3f v0[8], v1[8], v2[8];
    for (int l = 0; l < 8; ++l) {
      v0[l] = v3();
      v1[l] = v0[l] + v3() * 0.5f;
      v2[l] = v0[l] + v3() * 0.5f;
      if (iter % 7 == 0 && l == 3) v2[l] = v1[l];  // degenerate lane
    }
    const std::vector<float> words = make_leaf(v0, v1, v2, n);
    // Aimed at a random point of a random lane's plane, near or inside that triangle.
    const int k = iter % int(n);
    const float a = std::abs(u(rng)) * 0.6f, b = std::abs(u(rng)) * 0.6f;
    const Vec3f org = v3() * 2.0f;
    Ray r{org, 0.0f, (v0[k] + (v1[k] - v0[k]) * a + (v2[k] - v0[k]) * b) - org, iter % 3 ? 100.0f : 0.7f};
    if (iter % 11 == 0) r.dir.y = -0.0f;
    const LeafView lv(Leaf(words.data()));
    const TriHit8 h = moller_trumbore8(Vec3x8(r.org), Vec3x8(r.dir), lv.v0, lv.e1(), lv.e2(), float8(r.tnear), float8(r.tfar));
    for (int l = 0; l < 8; ++l) {
      if (l >= int(n)) {
        ASSERT_FALSE(lane_of(h, l).hit) << "lane " << l << " past a leaf of " << n;
        continue;
      }
      const Intersection<float> s = intersect_triangle_mt_normal(r, v0[l], v1[l], v2[l]);
      ASSERT_EQ(lane_of(h, l).hit, s.hit) << "iter " << iter << " lane " << l;
      if (!s.hit) continue;
      ++hits;
      expect_same_bits(lane_of(h, l), s);
      // The same triangle broadcast against the ray broadcast (the packet form).
      const TriHit8 p = moller_trumbore8(Vec3x8(r.org), Vec3x8(r.dir), Vec3x8(v0[l]), Vec3x8(v0[l] - v1[l]),
                                     Vec3x8(v2[l] - v0[l]), float8(r.tnear), float8(r.tfar));
      EXPECT_EQ(simd::movemask(p.hit), 0xffu);
      EXPECT_EQ(std::bit_cast<uint32_t>(simd::reduce_min(p.t)), std::bit_cast<uint32_t>(s.t));
    }
  }
  EXPECT_GT(hits, 1000);
}

/// Slab ×8 is conservative against the scalar slab test of core/geometry/slab.h: it never
/// misses a box the scalar test hits, and extra hits are within its padding.
TEST(Kernels, SlabTestsAreConservativeAgainstTheScalarSlab) {
  std::mt19937 rng(6);
  std::uniform_real_distribution<float> u(-2.0f, 2.0f);
  std::uniform_int_distribution<int> pick(0, 5);
  int hits = 0;
  for (int iter = 0; iter < 20000; ++iter) {
    Bvh8Node n;
    Box3f boxes[8];
    for (int c = 0; c < 8; ++c) {
      Vec3f a{u(rng), u(rng), u(rng)}, b{u(rng), u(rng), u(rng)};
      if (c == 2) b.y = a.y;  // a flat box
      boxes[c] = Box3f(min(a, b), max(a, b));
      n.lo_x[c] = boxes[c].lo.x; n.lo_y[c] = boxes[c].lo.y; n.lo_z[c] = boxes[c].lo.z;
      n.hi_x[c] = boxes[c].hi.x; n.hi_y[c] = boxes[c].hi.y; n.hi_z[c] = boxes[c].hi.z;
      n.child[c] = c;
    }
    Ray r{{u(rng) * 2, u(rng) * 2, u(rng) * 2}, 0.0f, {u(rng), u(rng), u(rng)}, 10.0f};
    // Axis-parallel rays with +-0 and origins on box faces.
    const int special = pick(rng);
    if (special == 0) r.dir = {0.0f, -0.0f, 1.0f};
    if (special == 1) { r.dir = {-0.0f, 1.0f, 0.0f}; r.org.x = boxes[iter % 8].lo.x; r.org.z = boxes[iter % 8].hi.z; }
    float8 t_enter;
    const uint32_t bits = intersect_node(n, SingleRay(r), r.tnear, r.tfar, t_enter);
    RayPacket p;
    p.org = Vec3x8(r.org);
    p.dir = Vec3x8(r.dir);
    p.inv = {float8(1.0f) / p.dir.x, float8(1.0f) / p.dir.y, float8(1.0f) / p.dir.z};
    p.neg_x = simd::sign_mask(p.dir.x);
    p.neg_y = simd::sign_mask(p.dir.y);
    p.neg_z = simd::sign_mask(p.dir.z);
    p.tnear = float8(r.tnear);
    p.oi = {p.org.x * p.inv.x, p.org.y * p.inv.y, p.org.z * p.inv.z};
    p.abs_pad = xsimd::max(xsimd::abs(p.oi.x), xsimd::max(xsimd::abs(p.oi.y), xsimd::abs(p.oi.z))) * float8(0x1p-23f);
    const bool octant_ok = r.dir.x != 0.0f && r.dir.y != 0.0f && r.dir.z != 0.0f;
    const bool neg[3] = {std::signbit(r.dir.x), std::signbit(r.dir.y), std::signbit(r.dir.z)};
    for (int c = 0; c < 8; ++c) {
      const SlabHit<float> s = rp::intersect_box(r, boxes[c]);
      const bool simd_hit = bits >> c & 1u;
      const bool packet_hit = intersect_box(p, boxes[c].lo, boxes[c].hi, float8(r.tfar)) == 0xffu;
      EXPECT_EQ(simd_hit, packet_hit) << "iter " << iter << " child " << c;
      if (octant_ok) {
        const bool octant_hit = intersect_box_octant(p, neg, boxes[c].lo, boxes[c].hi, float8(r.tfar)) == 0xffu;
        EXPECT_TRUE(!s.hit || octant_hit) << "iter " << iter << " child " << c << ": the one-octant packet test missed a box";
      }
      if (s.hit) {
        ++hits;
        EXPECT_TRUE(simd_hit) << "iter " << iter << " child " << c << ": the 8-wide slab test missed a box: org ("
                              << r.org.x << ", " << r.org.y << ", " << r.org.z << ") dir (" << r.dir.x << ", "
                              << r.dir.y << ", " << r.dir.z << ") box (" << boxes[c].lo.x << ", " << boxes[c].lo.y
                              << ", " << boxes[c].lo.z << ")-(" << boxes[c].hi.x << ", " << boxes[c].hi.y << ", "
                              << boxes[c].hi.z << ") scalar [" << s.t_enter << ", " << s.t_exit << "]";
      } else if (simd_hit) {
        const SlabHit<double> d = rp::intersect_box(Rayd{Vec3d(r.org), 0.0, Vec3d(r.dir), 10.0}, Box3d(Vec3d(boxes[c].lo), Vec3d(boxes[c].hi)));
        EXPECT_TRUE(d.hit || d.t_enter - d.t_exit <= 1e-6 * std::max(1.0, std::abs(d.t_exit)))
            << "iter " << iter << " child " << c << ": a hit well outside the box";
      }
    }
  }
  EXPECT_GT(hits, 5000);
}

// The ray-stream traversal works its rays' slab figures out 8 at a time; they must be the
// scalar SlabRay's bits, since a stream ray that leaves the stream (SingleRay from them) must
// test boxes exactly as the single-ray traversal does. Random rays, and the cases SlabRay
// treats apart: +-0 components, directions small enough that 1/d or org/d overflows, origins
// far out, and components of either sign.
TEST(Kernels, SlabRays8EqualsSlabRayLaneByLane) {
  std::mt19937 rng(21);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::uniform_int_distribution<int> pick(0, 9);
  const float specials[] = {0.0f, -0.0f, 0x1p-130f, -0x1p-130f, 0x1p-127f, 1e-30f, -1e-20f, 0x1p31f, 3.0f, -0.5f};
  int exact = 0;
  for (int iter = 0; iter < 4000; ++iter) {
    Ray rays[8];
    for (Ray& r : rays) {
      r = {{u(rng) * 100.0f, u(rng), u(rng) * 0x1p30f}, 0.0f, {u(rng), u(rng), u(rng)}, 1.0f};
      for (int a = 0; a < 3; ++a)
        if (pick(rng) < 3) r.dir[a] = specials[pick(rng)];
    }
    simd::Spill<6> rows;
    for (int l = 0; l < 8; ++l)
      for (int a = 0; a < 3; ++a) {
        rows.lanes[a][l] = rays[l].org[a];
        rows.lanes[3 + a][l] = rays[l].dir[a];
      }
    const SlabRays8 eight({rows.load(0), rows.load(1), rows.load(2)}, {rows.load(3), rows.load(4), rows.load(5)});
    for (int l = 0; l < 8; ++l) {
      const SlabRay want(rays[l]), got = eight.lane(l);
      exact += want.exact;
      ASSERT_EQ(got.exact, want.exact) << "iter " << iter << " lane " << l;
      for (int a = 0; a < 3; ++a) {
        ASSERT_EQ(got.near[a], want.near[a]) << "iter " << iter << " lane " << l << " axis " << a;
        ASSERT_EQ(std::bit_cast<uint32_t>(got.inv[a]), std::bit_cast<uint32_t>(want.inv[a])) << "iter " << iter;
        ASSERT_EQ(std::bit_cast<uint32_t>(got.oi[a]), std::bit_cast<uint32_t>(want.oi[a])) << "iter " << iter;
      }
      ASSERT_EQ(std::bit_cast<uint32_t>(got.pad), std::bit_cast<uint32_t>(want.pad))
          << "iter " << iter << " lane " << l << ": pad " << got.pad << " against " << want.pad;
    }
  }
  EXPECT_GT(exact, 1000);  // the exact form's cases were met
}

}  // namespace
}  // namespace rp::bvh8
