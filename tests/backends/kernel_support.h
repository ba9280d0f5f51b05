#pragma once
// What the tests of the 8-wide kernels share: a lane of a result as a scalar, bit-for-bit
// comparison, and a leaf written as the build writes it. AVX2+FMA test sources only.

#include <bit>
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>

#include "backends/simd/bvh8.h"
#include "backends/simd/moller_trumbore.h"
#include "core/geometry/triangle.h"

namespace rp::bvh8 {

/// Lane l of an 8-wide triangle test's result, as a scalar Intersection.
inline Intersection<float> lane_of(const TriHit8& h, int l) {
  alignas(32) float t[8], u[8], v[8];
  h.t.store_aligned(t);
  h.u.store_aligned(u);
  h.v.store_aligned(v);
  return {bool(simd::movemask(h.hit) >> l & 1u), t[l], u[l], v[l]};
}

/// The same t, u and v, bit for bit.
inline void expect_same_bits(const Intersection<float>& a, const Intersection<float>& b) {
  EXPECT_EQ(std::bit_cast<uint32_t>(a.t), std::bit_cast<uint32_t>(b.t));
  EXPECT_EQ(std::bit_cast<uint32_t>(a.u), std::bit_cast<uint32_t>(b.u));
  EXPECT_EQ(std::bit_cast<uint32_t>(a.v), std::bit_cast<uint32_t>(b.v));
}

/// The leaf the build would write for n primitives (prim_ids 0..n-1) with corners v0, v1,
/// v2, followed by floats of any value (what follows a leaf in the tree).
inline std::vector<float> make_leaf(const Vec3f* v0, const Vec3f* v1, const Vec3f* v2, uint32_t n) {
  std::vector<Vec3f> corners;
  std::vector<uint32_t> ids;
  for (uint32_t l = 0; l < n; ++l) {
    corners.insert(corners.end(), {v0[l], v1[l], v2[l]});
    ids.push_back(l);
  }
  std::vector<float> words(leaf_words(n, kMaxLeafVertices) + kLeafPad, 1.0f);
  write_leaf(words.data(), corners, ids);
  return words;
}

}  // namespace rp::bvh8
