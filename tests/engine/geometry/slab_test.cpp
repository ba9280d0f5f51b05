// The slab test against a brute-force clipping reference; signed zeros and infinite
// directions.

#include <gtest/gtest.h>

#include "tests/support/geometry.h"

namespace rp {
namespace {

using namespace rp::test;

struct SlabReference {
  bool hit;
  L t_enter, t_exit;
  L margin;  // smallest nonzero distance of a decision from flipping
};

/// Brute force in long double: clip (-inf, inf) by the six half-spaces one at a time
/// (x >= lo: t d >= lo - o; x <= hi: t d <= hi - o), no swap, no reciprocal.
template <typename T>
SlabReference slab_reference(const RayT<T>& r, const Box3<T>& b) {
  L lo_t = -std::numeric_limits<L>::infinity(), hi_t = std::numeric_limits<L>::infinity();
  bool empty = false;
  const auto clip = [&](L o, L d, L face, bool lower_face) {
    // Half-space: lower_face ? x >= face : x <= face.
    if (std::isinf(face) && ((face < 0) == lower_face)) return;  // all of space
    const L rhs = face - o;
    if (d == 0) {
      if (lower_face ? (0 < rhs) : (0 > rhs)) empty = true;
      return;
    }
    const L t = rhs / d;
    const bool t_is_lower = (d > 0) == lower_face;
    if (t_is_lower) lo_t = std::max(lo_t, t);
    else hi_t = std::min(hi_t, t);
  };
  for (int k = 0; k < 3; ++k) {
    clip(r.org[k], r.dir[k], b.lo[k], true);
    clip(r.org[k], r.dir[k], b.hi[k], false);
  }
  SlabReference ref{false, lo_t, hi_t, std::numeric_limits<L>::infinity()};
  if (empty) return ref;
  ref.hit = lo_t <= hi_t && lo_t <= L(r.tfar) && hi_t >= L(r.tnear);
  for (L m : {hi_t - lo_t, L(r.tfar) - lo_t, hi_t - L(r.tnear)}) {
    if (m != 0 && !std::isnan(m)) ref.margin = std::min(ref.margin, std::abs(m));
  }
  return ref;
}

template <typename T>
T special_or_random(std::mt19937& rng) {
  switch (rng() % 8) {
    case 0: return T(0);
    case 1: return -T(0);
    case 2: return kInfT<T>;
    case 3: return -kInfT<T>;
    case 4: return T(1);
    default: return uniform<T>(rng, -3, 3);
  }
}

template <typename T>
void check_slab_against_reference(unsigned seed, T tol) {
  std::mt19937 rng(seed);
  int checked = 0, hits = 0;
  for (int i = 0; i < 30000; ++i) {
    Vec3<T> lo = uniform_vec<T>(rng, -4, 4), hi = uniform_vec<T>(rng, -4, 4);
    Box3<T> box(min(lo, hi), max(lo, hi));
    if (rng() % 10 == 0) box.hi.x = box.lo.x;  // flat box
    Vec3<T> o = uniform_vec<T>(rng, -6, 6);
    const int where = int(rng() % 4);
    if (where == 1) o = box.lo + mul(box.extent(), uniform_vec<T>(rng, 0, 1));  // inside
    if (where == 2) {                                                            // on a face
      const int k = int(rng() % 3);
      o[k] = (rng() % 2) ? box.hi[k] : box.lo[k];
    }
    if (rng() % 10 == 0) box.lo.y = -kInfT<T>;  // unbounded face
    Vec3<T> d = uniform_vec<T>(rng, -3, 3);
    for (int k = 0; k < 3; ++k) {
      if (rng() % 3 == 0) d[k] = special_or_random<T>(rng);
    }
    RayT<T> r = make_ray(o, d);
    switch (rng() % 4) {
      case 1: r.tnear = -kInfT<T>; break;
      case 2:
        r.tnear = uniform<T>(rng, -2, 2);
        r.tfar = r.tnear + uniform<T>(rng, 0, 3);
        break;
      default: break;
    }
    const SlabHit<T> h = intersect_box(r, box);
    ASSERT_FALSE(std::isnan(h.t_enter) || std::isnan(h.t_exit)) << "case " << i;
    const SlabReference ref = slab_reference(r, box);
    const L scale = 1 + std::abs(ref.t_enter < -1e30L ? 0 : ref.t_enter) +
                    std::abs(ref.t_exit > 1e30L ? 0 : ref.t_exit);
    if (ref.margin < L(tol) * scale) continue;
    ++checked;
    hits += ref.hit;
    ASSERT_EQ(h.hit, ref.hit) << "case " << i;
    if (!h.hit) {
      EXPECT_EQ(h.t_enter, kInfT<T>);
      EXPECT_EQ(h.t_exit, -kInfT<T>);
      continue;
    }
    for (auto [got, want] : {std::pair<T, L>{h.t_enter, ref.t_enter}, {h.t_exit, ref.t_exit}}) {
      if (std::isinf(want)) {
        EXPECT_EQ(L(got), want) << "case " << i;
      } else {
        EXPECT_TRUE(close_rel<L>(got, want, L(tol))) << "case " << i << " " << got << " " << want;
      }
    }
  }
  EXPECT_GE(checked, 10000);
  EXPECT_GE(hits, 3000);
}

TEST(SlabProperty, AgreesWithBruteForceClippingReferenceFloat) {
  check_slab_against_reference<float>(1001, 1e-5f);
}

TEST(SlabProperty, AgreesWithBruteForceClippingReferenceDouble) {
  check_slab_against_reference<double>(1002, 1e-12);
}

TEST(SlabProperty, SignedZeroAndInfiniteDirectionsNeverGiveNaN) {
  const Box3f box({-1, -1, -1}, {1, 1, 1});
  const float specials[] = {0.0f, -0.0f, kInfT<float>, -kInfT<float>, 1.0f, -1.0f, 0.5f};
  const float origins[] = {-1.0f, 1.0f, 0.0f, -2.0f, 2.0f, -0.0f};  // faces, inside, outside
  int count = 0;
  for (float dx : specials) {
    for (float dy : specials) {
      for (float dz : specials) {
        for (float ox : origins) {
          for (float oy : origins) {
            const Ray r = make_ray<float>({ox, oy, 0.25f}, {dx, dy, dz});
            const SlabHit<float> h = intersect_box(r, box);
            ASSERT_FALSE(std::isnan(h.t_enter) || std::isnan(h.t_exit));
            EXPECT_EQ(h.hit, slab_reference(r, box).hit)
                << ox << "," << oy << " dir " << dx << "," << dy << "," << dz;
            ++count;
          }
        }
      }
    }
  }
  EXPECT_EQ(count, 7 * 7 * 7 * 6 * 6);
}

TEST(SlabProperty, AxisParallelRaysWithNegativeZeroComponents) {
  const Box3d box({-2, -2, -2}, {2, 2, 2});
  // Inside the y and z slabs (including exactly on their faces): hit over [1, 5] or [-5, -1].
  for (double oy : {0.0, -0.0, 2.0, -2.0}) {
    for (double dz : {0.0, -0.0}) {
      const SlabHit<double> fwd = intersect_box(make_ray<double>({-3, oy, -2}, {1, -0.0, dz}), box);
      ASSERT_TRUE(fwd.hit);
      EXPECT_EQ(fwd.t_enter, 1.0);
      EXPECT_EQ(fwd.t_exit, 5.0);
      const SlabHit<double> back =
          intersect_box(make_ray<double>({-3, oy, 2}, {-1, dz, -0.0}, -kInfT<double>), box);
      ASSERT_TRUE(back.hit);
      EXPECT_EQ(back.t_enter, -5.0);
      EXPECT_EQ(back.t_exit, -1.0);
      EXPECT_FALSE(intersect_box(make_ray<double>({-3, oy, 2}, {-1, dz, -0.0}), box).hit);
    }
  }
  // Outside a slab with a zero component: miss, for +0 and -0 alike.
  for (double dy : {0.0, -0.0}) {
    EXPECT_FALSE(intersect_box(make_ray<double>({-3, 2.5, 0}, {1, dy, 0}), box).hit);
    EXPECT_FALSE(intersect_box(make_ray<double>({-3, -2.5, 0}, {1, dy, -0.0}), box).hit);
  }
  // Origin inside, all-zero direction: the whole line is inside.
  const SlabHit<double> still = intersect_box(make_ray<double>({0, 0, 0}, {-0.0, 0, -0.0}), box);
  ASSERT_TRUE(still.hit);
  EXPECT_EQ(still.t_enter, -kInfT<double>);
  EXPECT_EQ(still.t_exit, kInfT<double>);
}

TEST(SlabProperty, RawIntervalIsNotClampedToTheRay) {
  const Box3d box({-2, -2, -2}, {2, 2, 2});
  const SlabHit<double> h = intersect_box(make_ray<double>({-3, 4, 5}, {1, -1, -2}, 2.5, 3.0), box);
  ASSERT_TRUE(h.hit);
  EXPECT_EQ(h.t_enter, 2.0);
  EXPECT_EQ(h.t_exit, 3.5);
  // Origin inside: t_enter is negative.
  const SlabHit<double> in = intersect_box(make_ray<double>({0, 0, 0}, {1, 0, 0}), box);
  ASSERT_TRUE(in.hit);
  EXPECT_EQ(in.t_enter, -2.0);
  EXPECT_EQ(in.t_exit, 2.0);
  // Box entirely behind: miss with the documented miss values.
  const SlabHit<double> miss = intersect_box(make_ray<double>({5, 0, 0}, {1, 0, 0}), box);
  EXPECT_FALSE(miss.hit);
  EXPECT_EQ(miss.t_enter, kInfT<double>);
  EXPECT_EQ(miss.t_exit, -kInfT<double>);
  // Empty default box: miss.
  EXPECT_FALSE(intersect_box(make_ray<double>({0, 0, 0}, {1, 0, 0}), Box3d{}).hit);
}

}  // namespace
}  // namespace rp
