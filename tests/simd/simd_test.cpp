// Tests for simd/float8.h and simd/float4.h: every helper against a plain scalar loop over its
// lanes, on seeded random packets and on hand-picked special values (NaN, +-inf, +-0,
// denormals, FLT_MAX) in every lane position.
//
// Build: this translation unit must be compiled for AVX2+FMA (-mavx2 -mfma, from rp::avx2) and
// with -ffp-contract=off (from rp::fp_strict); CMake gives both. Without -ffp-contract=off the
// compiler may fuse a*b + c into one FMA, in scalar or in 8-wide code, and the kernels lose
// the bits of their scalar twins; Float8Build.NoFmaContraction names that cause directly.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "base/math.h"
#include "base/pow.h"
#include "simd/float4.h"
#include "simd/float8.h"
#include "simd/pow8.h"

#if !defined(__AVX2__) || !defined(__FMA__)
#error "simd_test.cpp must be compiled for AVX2+FMA (-mavx2 -mfma; link rp::avx2)"
#endif

namespace rp::simd {
namespace {

using Lanes = std::array<float, 8>;

constexpr uint32_t kSeed = 0x5eed8;

constexpr float from_bits(uint32_t u) { return std::bit_cast<float>(u); }
constexpr uint32_t bits_of(float f) { return std::bit_cast<uint32_t>(f); }

float8 pack(const Lanes& l) { return float8::load_unaligned(l.data()); }
Lanes unpack(const float8& v) {
  Lanes l;
  v.store_unaligned(l.data());
  return l;
}

/// Hand-picked values: four NaNs (quiet, negative, with payload, signalling), infinities,
/// signed zeros, denormals, the normal extremes and a few ordinary numbers for ties.
constexpr std::array<float, 19> kSpecials = {
    from_bits(0x7fc00000), from_bits(0xffc00000), from_bits(0x7fc12345), from_bits(0x7f800001),
    std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
    0.0f, -0.0f,
    from_bits(0x00000001), from_bits(0x80000001), from_bits(0x007fffff),
    FLT_MIN, -FLT_MIN, FLT_MAX, -FLT_MAX,
    1.0f, -1.0f, 0.5f, 3.0f};
constexpr float kNan = from_bits(0x7fc00000);

float random_special(std::mt19937& rng) { return kSpecials[rng() % kSpecials.size()]; }

/// Mostly ordinary values in [-4, 4) (where rounding matters), with small integers (ties, exact
/// zeros), specials, and arbitrary bit patterns (any NaN, denormal or huge value) mixed in.
float random_float(std::mt19937& rng) {
  switch (rng() % 8) {
    case 0: return random_special(rng);
    case 1: return from_bits(rng());
    case 2: return float(int(rng() % 9) - 4);
    default: return std::uniform_real_distribution<float>(-4.0f, 4.0f)(rng);
  }
}

Lanes random_lanes(std::mt19937& rng) {
  Lanes l;
  for (float& f : l) f = random_float(rng);
  return l;
}

Lanes random_special_lanes(std::mt19937& rng) {
  Lanes l;
  for (float& f : l) f = random_special(rng);
  return l;
}

/// Calls f(a, b) with every ordered pair of kSpecials in every lane position: the pairs go in
/// chunks of eight, each chunk rotated through the eight lanes.
void for_each_special_pair(const std::function<void(const Lanes&, const Lanes&)>& f) {
  std::vector<std::pair<float, float>> pairs;
  for (float a : kSpecials)
    for (float b : kSpecials) pairs.emplace_back(a, b);
  for (size_t base = 0; base < pairs.size(); base += 8) {
    for (size_t r = 0; r < 8; ++r) {
      Lanes a, b;
      for (size_t k = 0; k < 8; ++k) {
        const auto& p = pairs[(base + (k + r) % 8) % pairs.size()];
        a[k] = p.first;
        b[k] = p.second;
      }
      f(a, b);
    }
  }
}

/// Random packets, special-only packets and every special pair in every lane.
std::vector<std::pair<Lanes, Lanes>> binary_cases(uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<std::pair<Lanes, Lanes>> cases;
  for (int i = 0; i < 4000; ++i) cases.emplace_back(random_lanes(rng), random_lanes(rng));
  for (int i = 0; i < 2000; ++i) cases.emplace_back(random_special_lanes(rng), random_special_lanes(rng));
  for_each_special_pair([&](const Lanes& a, const Lanes& b) { cases.emplace_back(a, b); });
  return cases;
}

std::string show(float f) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%g[0x%08x]", double(f), unsigned(bits_of(f)));
  return buf;
}
std::string show(const Lanes& l) {
  std::string s = "{";
  for (size_t i = 0; i < l.size(); ++i) s += (i ? ", " : "") + show(l[i]);
  return s + "}";
}
std::string show(const Vec3f& v) {
  std::string s("(");
  s += show(v.x);
  s += ", ";
  s += show(v.y);
  s += ", ";
  s += show(v.z);
  s += ")";
  return s;
}

/// Same bits, except that any two NaNs match: arithmetic may carry either operand's payload.
bool same_value(float a, float b) {
  if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
  return bits_of(a) == bits_of(b);
}
bool same_value(const Vec3f& a, const Vec3f& b) {
  return same_value(a.x, b.x) && same_value(a.y, b.y) && same_value(a.z, b.z);
}
/// Same bits, NaN payloads included (for data movement, which must not touch them).
bool same_bits(const Vec3f& a, const Vec3f& b) {
  return bits_of(a.x) == bits_of(b.x) && bits_of(a.y) == bits_of(b.y) && bits_of(a.z) == bits_of(b.z);
}

/// Collects mismatches and reports only the first few, so a broken helper can't print
/// thousands of failures; the test then checks count() == 0.
class Mismatches {
 public:
  void add(const std::string& what) {
    if (count_++ < kShown) ADD_FAILURE() << what;
  }
  int count() const { return count_; }

 private:
  static constexpr int kShown = 6;
  int count_ = 0;
};

TEST(Float8Build, NoFmaContraction) {
  // x*x = 1 + 2^-11 + 2^-24 rounds (tie to even) to 1 + 2^-11 = -c, so (x*x + 1*c) + 0*0 is 0
  // with every product rounded and 2^-24 when x*x + c is fused. volatile stops constant folding.
  volatile float vx = 1.0f + 0x1p-12f, vc = -(1.0f + 0x1p-11f);
  const Vec3f a{vx, 1.0f, 0.0f}, b{vx, vc, 0.0f};
  EXPECT_EQ(rp::dot(a, b), 0.0f) << "scalar code was FMA-contracted: compile with -ffp-contract=off";
  const float8 x(vx), c(vc), one(1.0f), zero(0.0f);
  EXPECT_EQ(unpack(x * x + one * c + zero * zero)[0], 0.0f)
      << "8-wide code was FMA-contracted: compile with -ffp-contract=off";
}

TEST(Movemask, MatchesScalarComparisonOfEachLane) {
  // Ordered comparisons: false on NaN lanes, in xsimd as in scalar C++. (xsimd's != is
  // NEQ_OQ, false on NaN unlike C++, so it is left out.)
  struct Op {
    const char* name;
    mask8 (*simd)(const float8&, const float8&);
    bool (*scalar)(float, float);
  };
  const Op ops[] = {
      {"<", [](const float8& a, const float8& b) { return a < b; }, [](float a, float b) { return a < b; }},
      {"<=", [](const float8& a, const float8& b) { return a <= b; }, [](float a, float b) { return a <= b; }},
      {">", [](const float8& a, const float8& b) { return a > b; }, [](float a, float b) { return a > b; }},
      {">=", [](const float8& a, const float8& b) { return a >= b; }, [](float a, float b) { return a >= b; }},
      {"==", [](const float8& a, const float8& b) { return a == b; }, [](float a, float b) { return a == b; }},
  };
  Mismatches bad;
  for (const auto& [a, b] : binary_cases(kSeed)) {
    for (const Op& op : ops) {
      uint32_t want = 0;
      for (int i = 0; i < 8; ++i) want |= uint32_t(op.scalar(a[i], b[i])) << i;
      const uint32_t got = movemask(op.simd(pack(a), pack(b)));
      if (got != want)
        bad.add("a " + show(a) + " " + op.name + " b " + show(b) + ": want " + std::to_string(want) +
                " got " + std::to_string(got));
    }
  }
  EXPECT_EQ(bad.count(), 0);
}

TEST(MaskFromBits, RoundTripsThroughMovemaskForAll256Patterns) {
  for (uint32_t bits = 0; bits < 256; ++bits) {
    const mask8 m = mask_from_bits(bits);
    EXPECT_EQ(movemask(m), bits);
    // Each lane is all ones or all zeros, as a comparison would give; xsimd's select needs that.
    alignas(32) int32_t lanes[8];
    store_mask(lanes, m);
    for (int i = 0; i < 8; ++i) EXPECT_EQ(lanes[i], (bits >> i) & 1 ? -1 : 0) << "bits " << bits << " lane " << i;
    // Only bits 0..7 name lanes.
    EXPECT_EQ(movemask(mask_from_bits(bits | 0xabcdef00u)), bits);
  }
}

TEST(Spill, GivesEachValuesLanesAndLoadsBackWhatTheScalarLoopWrote) {
  std::mt19937 rng(kSeed + 3);
  std::uniform_int_distribution<size_t> pick(0, kSpecials.size() - 1);
  for (int round = 0; round < 50; ++round) {
    Lanes a, b, c;
    for (int l = 0; l < 8; ++l) a[l] = kSpecials[pick(rng)], b[l] = kSpecials[pick(rng)], c[l] = kSpecials[pick(rng)];
    Spill<3> s(pack(a), pack(b), pack(c));
    const Lanes* in[3] = {&a, &b, &c};
    for (size_t k = 0; k < 3; ++k)
      for (int l = 0; l < 8; ++l) EXPECT_EQ(bits_of(s.lanes[k][l]), bits_of((*in[k])[l])) << "value " << k << " lane " << l;
    const int edited = round % 8;  // one lane of the middle value rewritten by "scalar code"
    s.lanes[1][edited] = float(round);
    b[edited] = float(round);
    for (size_t k = 0; k < 3; ++k) {
      const Lanes back = unpack(s.load(k));
      for (int l = 0; l < 8; ++l) EXPECT_EQ(bits_of(back[l]), bits_of((*in[k])[l])) << "value " << k << " lane " << l;
    }
  }
}

TEST(LoadUnalignedNanPast, KeepsTheFirstNLanesBitExactlyAndSetsEveryBitOfTheRest) {
  std::mt19937 rng(kSeed + 7);
  for (int round = 0; round < 50; ++round) {
    uint32_t in[16];
    for (uint32_t& b : in) b = rng();  // every bit pattern: NaNs, -0, denormals included
    float block[16];
    std::memcpy(block, in, sizeof in);
    for (uint32_t n = 0; n <= 8; ++n)
      for (int at = 0; at < 8; ++at) {  // every alignment of the first float
        const Lanes got = unpack(load_unaligned_nan_past(block + at, nan_past(n)));
        for (uint32_t i = 0; i < 8; ++i)
          ASSERT_EQ(bits_of(got[i]), i < n ? in[size_t(at) + i] : 0xffffffffu)
              << "n " << n << " at " << at << " lane " << i;
      }
  }
}

/// x86 MINPS/MAXPS per lane: a if a < b (a > b) else b, so NaN in either operand and equal
/// operands (-0 vs +0) give b.
float minps(float a, float b) { return a < b ? a : b; }
float maxps(float a, float b) { return a > b ? a : b; }

void expect_lanewise_bits(const char* name, float8 (*simd)(const float8&, const float8&),
                          float (*scalar)(float, float)) {
  Mismatches bad;
  for (const auto& [a, b] : binary_cases(kSeed + 1)) {
    const Lanes got = unpack(simd(pack(a), pack(b)));
    for (int i = 0; i < 8; ++i) {
      const float want = scalar(a[i], b[i]);
      if (bits_of(got[i]) != bits_of(want))
        bad.add(std::string(name) + " lane " + std::to_string(i) + ": a " + show(a[i]) + " b " + show(b[i]) +
                ": want " + show(want) + " got " + show(got[i]));
    }
  }
  EXPECT_EQ(bad.count(), 0);
}

TEST(MinBOnNan, MatchesMinpsRuleBitExactly) { expect_lanewise_bits("min_b_on_nan", min_b_on_nan, minps); }
TEST(MaxBOnNan, MatchesMaxpsRuleBitExactly) { expect_lanewise_bits("max_b_on_nan", max_b_on_nan, maxps); }

TEST(MinBOnNan, NanOrEqualLanesGiveB) {
  const float inf = std::numeric_limits<float>::infinity();
  const Lanes a = {kNan, 2.0f, kNan, -0.0f, 0.0f, from_bits(0x7fc12345), inf, -inf};
  const Lanes b = {1.0f, kNan, from_bits(0xffc00000), 0.0f, -0.0f, -inf, kNan, 5.0f};
  const Lanes mn = unpack(min_b_on_nan(pack(a), pack(b)));
  const Lanes mx = unpack(max_b_on_nan(pack(a), pack(b)));
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(bits_of(mn[i]), bits_of(b[i])) << "min lane " << i;
    EXPECT_EQ(bits_of(mx[i]), bits_of(b[i])) << "max lane " << i;
  }
  EXPECT_TRUE(std::isnan(mn[6]));
  EXPECT_TRUE(std::isnan(mx[6]));
  EXPECT_EQ(mn[7], -inf);
  EXPECT_EQ(mx[7], 5.0f);
}

/// The documented meaning of max_bits / min_bits / greater_bits: the bit patterns compared as
/// signed 32-bit integers, lane by lane.
float max_as_int(float a, float b) { return std::bit_cast<int32_t>(a) > std::bit_cast<int32_t>(b) ? a : b; }
float min_as_int(float a, float b) { return std::bit_cast<int32_t>(a) < std::bit_cast<int32_t>(b) ? a : b; }

TEST(MaxBits, MatchesIntegerMaxOfTheBitsExactly) { expect_lanewise_bits("max_bits", max_bits, max_as_int); }
TEST(MinBits, MatchesIntegerMinOfTheBitsExactly) { expect_lanewise_bits("min_bits", min_bits, min_as_int); }

TEST(MaxBits, EqualsTheFloatOrderWhereTheSlabTestUsesIt) {
  // The slab test's promise (simd::max_bits): for non-NaN floats, max_bits is the float max
  // whenever one operand is >= +0, and min_bits the float min when both are >= +0 and
  // negative whenever the float min is.
  std::mt19937 rng(kSeed + 7);
  const float inf = std::numeric_limits<float>::infinity();
  for (int round = 0; round < 20000; ++round) {
    Lanes a, b;
    for (int i = 0; i < 8; ++i) {
      do a[i] = random_float(rng); while (std::isnan(a[i]));
      do b[i] = random_float(rng); while (std::isnan(b[i]));
      if (rng() % 4 == 0) a[i] = rng() % 2 ? inf : -inf;
    }
    const Lanes mx = unpack(max_bits(pack(a), pack(b))), mn = unpack(min_bits(pack(a), pack(b)));
    const uint32_t gt = greater_bits(pack(a), pack(b));
    for (int i = 0; i < 8; ++i) {
      const bool a_pos = !std::signbit(a[i]), b_pos = !std::signbit(b[i]);
      if (a_pos || b_pos) {
        ASSERT_EQ(mx[i], std::max(a[i], b[i])) << show(a[i]) << " " << show(b[i]);
      }
      if (a_pos && b_pos) {
        ASSERT_EQ(mn[i], std::min(a[i], b[i])) << show(a[i]) << " " << show(b[i]);
        ASSERT_EQ(bool(gt >> i & 1u), a[i] > b[i] || (a[i] == b[i] && bits_of(a[i]) > bits_of(b[i])));
      }
      if (std::min(a[i], b[i]) < 0.0f) {
        ASSERT_TRUE(std::signbit(mn[i])) << show(a[i]) << " " << show(b[i]);
      }
      ASSERT_EQ(bool(gt >> i & 1u), std::bit_cast<int32_t>(a[i]) > std::bit_cast<int32_t>(b[i]));
    }
  }
}

TEST(CompressStore, WritesThePickedLanesInOrderForAll256Masks) {
  std::mt19937 rng(kSeed + 8);
  uint32_t src[8];
  for (uint32_t& v : src) v = rng();
  for (uint32_t mask = 0; mask < 256; ++mask) {
    uint32_t dst[8];
    std::fill_n(dst, 8, 0xdeadbeefu);
    const uint32_t n = compress_store(src, mask, dst);
    std::vector<uint32_t> want;
    for (int l = 0; l < 8; ++l)
      if (mask >> l & 1u) want.push_back(src[l]);
    ASSERT_EQ(n, want.size()) << "mask " << mask;
    for (size_t k = 0; k < want.size(); ++k) ASSERT_EQ(dst[k], want[k]) << "mask " << mask << " slot " << k;
    // The slots past the count hold the lanes that were not picked (each value of src once).
    std::vector<uint32_t> all(dst, dst + 8), lanes(src, src + 8);
    std::sort(all.begin(), all.end());
    std::sort(lanes.begin(), lanes.end());
    ASSERT_EQ(all, lanes) << "mask " << mask;
  }
}

TEST(ByteBits8, GivesBitCOfEachOfEightBytes) {
  std::mt19937 rng(kSeed + 9);
  for (int round = 0; round < 1000; ++round) {
    uint8_t bytes[8];
    for (uint8_t& b : bytes) b = uint8_t(rng());
    const ByteBits8 bb(bytes);
    for (int c = 0; c < 8; ++c) {
      uint32_t want = 0;
      for (int l = 0; l < 8; ++l) want |= uint32_t(bytes[l] >> c & 1u) << l;
      ASSERT_EQ(bb.bit(c), want) << "bit " << c;
    }
  }
}

TEST(Count8, CountsEachBitOverTheMasksAdded) {
  std::mt19937 rng(kSeed + 10);
  Count8 counts;
  uint32_t want[8] = {};
  for (int k = 0; k < 5000; ++k) {
    const uint32_t m = rng() & 0xffu;
    counts.add(m);
    for (int c = 0; c < 8; ++c) want[c] += m >> c & 1u;
  }
  alignas(32) uint32_t got[8];
  counts.store(got);
  for (int c = 0; c < 8; ++c) EXPECT_EQ(got[c], want[c]) << "lane " << c;
}

/// Bases and exponents as Blinn-Phong uses them (cosines in [0, 1] and a little above, the
/// exponents of MTL files) and around them: zeros, denormals, 1, large exponents, and a few
/// lanes outside the domain (negative, NaN, inf) that go to std::pow.
std::pair<float, float> random_pow_args(std::mt19937& rng) {
  float x, y;
  switch (rng() % 8) {
    case 0: x = from_bits(rng() % 0x00800000u); break;         // denormals and 0
    case 1: x = 1.0f + float(rng() % 64) * 0x1p-23f; break;       // 1 and just above
    case 2: x = from_bits(rng() & 0x7fffffffu); break;            // any non-negative bits (NaN, inf too)
    default: x = std::uniform_real_distribution<float>(0.0f, 1.0f)(rng);
  }
  switch (rng() % 6) {
    case 0: y = float(rng() % 9); break;                           // 0..8
    case 1: y = std::uniform_real_distribution<float>(0.0f, 1.0f)(rng); break;
    case 2: y = float(rng() % 2000); break;
    case 3: y = rng() % 50 == 0 ? -1.0f : std::uniform_real_distribution<float>(0.0f, 1e4f)(rng); break;
    default: y = std::uniform_real_distribution<float>(1.0f, 200.0f)(rng);
  }
  return {x, y};
}

TEST(Pow8, EveryLaneHasTheScalarRoutinesBits) {
  std::mt19937 rng(kSeed + 11);
  for (int round = 0; round < 200000; ++round) {
    Lanes x, y;
    for (int i = 0; i < 8; ++i) std::tie(x[i], y[i]) = random_pow_args(rng);
    const Lanes got = unpack(pow8(pack(x), pack(y)));
    for (int i = 0; i < 8; ++i) {
      const float want = pow_nonneg(x[i], y[i]);
      ASSERT_TRUE(bits_of(got[i]) == bits_of(want) || (std::isnan(got[i]) && std::isnan(want)))
          << "pow(" << show(x[i]) << ", " << show(y[i]) << "): lane " << i << " " << show(got[i]) << ", scalar "
          << show(want);
    }
  }
}

TEST(PowNonneg, WithinOneUlpOfLibmsPowf) {
  // The bound base/pow.h states: both are within an ulp of the exact power, and they agree
  // bit for bit on most arguments.
  std::mt19937 rng(kSeed + 12);
  int differ = 0, n = 0;
  for (int k = 0; k < 2000000; ++k) {
    const auto [x, y] = random_pow_args(rng);
    const float got = pow_nonneg(x, y), want = std::pow(x, y);
    ++n;
    if (std::isnan(want)) {
      ASSERT_TRUE(std::isnan(got)) << show(x) << " " << show(y);
      continue;
    }
    const int64_t ulps = std::abs(int64_t(bits_of(got)) - int64_t(bits_of(want)));
    ASSERT_LE(ulps, 1) << "pow(" << show(x) << ", " << show(y) << ") = " << show(got) << ", powf " << show(want);
    differ += ulps != 0;
  }
  std::printf("pow_nonneg: %d of %d results one ulp from powf, the rest equal\n", differ, n);
  EXPECT_LT(differ, n / 100);
}

/// The scalar oracle: min (max) over the non-NaN lanes; NaN when every lane is NaN.
float scalar_reduce(const Lanes& l, bool want_min) {
  float r = kNan;
  for (float x : l)
    if (!std::isnan(x) && (std::isnan(r) || (want_min ? x < r : x > r))) r = x;
  return r;
}

/// Where -0 and +0 tie for the extreme either sign is accepted: only the value is checked, and
/// that the bits are some non-NaN input lane's.
bool reduce_matches(const Lanes& l, float got, bool want_min) {
  const float want = scalar_reduce(l, want_min);
  if (std::isnan(want)) return std::isnan(got);
  if (!(got == want)) return false;
  for (float x : l)
    if (!std::isnan(x) && bits_of(x) == bits_of(got)) return true;
  return false;
}

void expect_reduce_matches(bool want_min, const std::vector<Lanes>& packets) {
  Mismatches bad;
  for (const Lanes& l : packets) {
    const float got = want_min ? reduce_min(pack(l)) : reduce_max(pack(l));
    if (!reduce_matches(l, got, want_min))
      bad.add(std::string(want_min ? "reduce_min " : "reduce_max ") + show(l) + ": want " +
              show(scalar_reduce(l, want_min)) + " got " + show(got));
  }
  EXPECT_EQ(bad.count(), 0) << "of " << packets.size() << " packets";
}

/// Random lanes; half the packets also get a random set of lanes replaced by NaN.
std::vector<Lanes> random_reduce_packets() {
  std::mt19937 rng(kSeed + 2);
  std::vector<Lanes> packets;
  for (int i = 0; i < 20000; ++i) {
    Lanes l = random_lanes(rng);
    if (i % 2) {
      const uint32_t nan_lanes = rng() & 0xff;
      for (int k = 0; k < 8; ++k)
        if ((nan_lanes >> k) & 1) l[k] = kNan;
    }
    packets.push_back(l);
  }
  return packets;
}

/// Each special alone in each lane over a background of each special (one NaN, all NaN but one,
/// lone -inf, ...), then random mixtures of specials.
std::vector<Lanes> special_reduce_packets() {
  std::vector<Lanes> packets;
  for (float s : kSpecials)
    for (float background : kSpecials)
      for (int k = 0; k < 8; ++k) {
        Lanes l;
        l.fill(background);
        l[k] = s;
        packets.push_back(l);
      }
  std::mt19937 rng(kSeed + 3);
  for (int i = 0; i < 5000; ++i) packets.push_back(random_special_lanes(rng));
  return packets;
}

/// Every set of NaN lanes with the extreme in every remaining lane; the other lanes distinct
/// finite values. The 255 pattern (all NaN) must give NaN.
std::vector<Lanes> nan_pattern_packets(bool want_min) {
  std::vector<Lanes> packets;
  for (uint32_t nan_lanes = 0; nan_lanes < 256; ++nan_lanes) {
    for (int extreme = 0; extreme < 8; ++extreme) {
      if ((nan_lanes >> extreme) & 1 && nan_lanes != 255) continue;
      Lanes l;
      for (int k = 0; k < 8; ++k) l[k] = (nan_lanes >> k) & 1 ? kNan : 10.0f + float(k);
      if (nan_lanes != 255) l[extreme] = want_min ? -5.0f : 50.0f;
      packets.push_back(l);
    }
  }
  return packets;
}

TEST(ReduceMin, MatchesScalarMinOverRandomLanes) { expect_reduce_matches(true, random_reduce_packets()); }
TEST(ReduceMax, MatchesScalarMaxOverRandomLanes) { expect_reduce_matches(false, random_reduce_packets()); }
TEST(ReduceMin, MatchesScalarMinOverSpecialValues) { expect_reduce_matches(true, special_reduce_packets()); }
TEST(ReduceMax, MatchesScalarMaxOverSpecialValues) { expect_reduce_matches(false, special_reduce_packets()); }
TEST(ReduceMin, IgnoresNanLanesInEveryPattern) { expect_reduce_matches(true, nan_pattern_packets(true)); }
TEST(ReduceMax, IgnoresNanLanesInEveryPattern) { expect_reduce_matches(false, nan_pattern_packets(false)); }

TEST(LaneCount, MatchesScalarCountForAllPatterns) {
  for (uint32_t bits = 0; bits < 256; ++bits) {
    int want = 0;
    for (int i = 0; i < 8; ++i) want += (bits >> i) & 1;
    EXPECT_EQ(lane_count(bits), want) << "bits " << bits;
  }
}

TEST(BroadcastLane, CopiesTheChosenLaneBitExactlyToEveryLane) {
  alignas(32) const uint32_t in[8] = {0x7fc00001u, 0x80000000u, 0x00000001u, 0x3f800000u,
                                      0xff800000u, 0x7f7fffffu, 0xbf000000u, 0x12345678u};
  float8 v;
  std::memcpy(&v, in, 32);
  for (int i = 0; i < 8; ++i) {
    alignas(32) uint32_t out[8];
    const float8 b = broadcast_lane(v, i);
    std::memcpy(out, &b, 32);
    for (int l = 0; l < 8; ++l) EXPECT_EQ(out[l], in[i]) << "lane " << i << " into " << l;
    const Vec3x8 three{v, v, v};
    EXPECT_EQ(std::bit_cast<uint32_t>(three.broadcast(i).lane(5).z), in[i]);
  }
}

using Lanes4 = std::array<float, 4>;

Lanes4 unpack4(float4 v) {
  alignas(16) Lanes4 l;
  store4(l.data(), v);
  return l;
}

TEST(Float4, Load3KeepsThreeLanesBitExactlyAndZeroesTheFourth) {
  std::mt19937 rng(kSeed + 8);
  for (int round = 0; round < 1000; ++round) {
    uint32_t in[4];
    for (uint32_t& b : in) b = rng();  // every bit pattern, the fourth too
    float block[4];
    std::memcpy(block, in, sizeof in);
    const Lanes4 got = unpack4(load3(block));
    for (int i = 0; i < 3; ++i) ASSERT_EQ(bits_of(got[size_t(i)]), in[i]) << "lane " << i;
    ASSERT_EQ(bits_of(got[3]), 0u);
    const Lanes4 all = unpack4(load4(block));
    for (int i = 0; i < 4; ++i) ASSERT_EQ(bits_of(all[size_t(i)]), in[i]) << "load4 lane " << i;
  }
}

TEST(Float4, MinAndMaxMatchTheMinpsRuleBitExactly) {
  Mismatches bad;
  for (const auto& [a, b] : binary_cases(kSeed + 9))
    for (size_t half = 0; half < 8; half += 4) {
      const Lanes4 mn = unpack4(min4(load4(a.data() + half), load4(b.data() + half)));
      const Lanes4 mx = unpack4(max4(load4(a.data() + half), load4(b.data() + half)));
      for (size_t i = 0; i < 4; ++i)
        if (bits_of(mn[i]) != bits_of(minps(a[half + i], b[half + i])) ||
            bits_of(mx[i]) != bits_of(maxps(a[half + i], b[half + i])))
          bad.add("a " + show(a[half + i]) + " b " + show(b[half + i]) + ": min " + show(mn[i]) + " max " +
                  show(mx[i]));
    }
  EXPECT_EQ(bad.count(), 0);
}

TEST(Float4, TruncateAndClampGiveTheScalarBinIndex) {
  // The builder's bin index, 4-wide, against its scalar form std::clamp(int(x), 0, top) over
  // values around every bin edge of 8, 16 and 32 bins, and beyond either end.
  std::mt19937 rng(kSeed + 10);
  for (int32_t top : {7, 15, 31}) {
    for (int round = 0; round < 5000; ++round) {
      alignas(16) Lanes4 x;
      for (float& f : x) f = std::uniform_real_distribution<float>(-2.0f, float(top) + 3.0f)(rng);
      if (round % 4 == 0) x[size_t(round / 4 % 4)] = float(round / 16 % (top + 2));  // exactly on an edge
      alignas(16) int32_t got[4];
      store4(got, min4(max4(truncate4(load4(x.data())), splat4(0)), splat4(top)));
      for (size_t i = 0; i < 4; ++i) ASSERT_EQ(got[i], std::clamp(int(x[i]), 0, top)) << show(x[i]) << " top " << top;
    }
  }
}

/// Eight 3-vectors in SoA, aligned for Vec3x8::load.
struct SoA {
  alignas(32) Lanes x, y, z;

  Vec3x8 load() const { return Vec3x8::load(x.data(), y.data(), z.data()); }
  Vec3f lane(int i) const { return {x[i], y[i], z[i]}; }
  Lanes& component(int c) { return c == 0 ? x : c == 1 ? y : z; }
};

struct Vec3Case {
  SoA a, b;
};

/// Random cases, special-only cases, and every ordered pair of specials in every lane of each
/// component of a and b (the other components random).
std::vector<Vec3Case> vec3_cases() {
  std::mt19937 rng(kSeed + 5);
  std::vector<Vec3Case> cases;
  for (int i = 0; i < 6000; ++i) {
    const bool special = i % 3 == 2;
    auto gen = [&] { return special ? random_special_lanes(rng) : random_lanes(rng); };
    Vec3Case c;
    c.a.x = gen(), c.a.y = gen(), c.a.z = gen();
    c.b.x = gen(), c.b.y = gen(), c.b.z = gen();
    cases.push_back(c);
  }
  for (int comp = 0; comp < 3; ++comp) {
    for_each_special_pair([&](const Lanes& pa, const Lanes& pb) {
      Vec3Case c;
      c.a.x = random_lanes(rng), c.a.y = random_lanes(rng), c.a.z = random_lanes(rng);
      c.b.x = random_lanes(rng), c.b.y = random_lanes(rng), c.b.z = random_lanes(rng);
      c.a.component(comp) = pa;
      c.b.component(comp) = pb;
      cases.push_back(c);
    });
  }
  return cases;
}

/// Checks got.lane(i) against want(i) for every lane of every case, NaNs matching any NaN.
void expect_vec3_op(const char* name, const std::function<Vec3x8(const Vec3Case&)>& simd,
                    const std::function<Vec3f(const Vec3Case&, int)>& scalar) {
  Mismatches bad;
  for (const Vec3Case& c : vec3_cases()) {
    const Vec3x8 got = simd(c);
    for (int i = 0; i < 8; ++i) {
      const Vec3f want = scalar(c, i);
      if (!same_value(got.lane(i), want))
        bad.add(std::string(name) + " lane " + std::to_string(i) + ": a " + show(c.a.lane(i)) + " b " +
                show(c.b.lane(i)) + ": want " + show(want) + " got " + show(got.lane(i)));
    }
  }
  EXPECT_EQ(bad.count(), 0);
}

/// transpose8x8 on rows in registers, and load_transposed8x8 from eight records in memory
/// (unaligned): lane i of row j is word j of record i, every bit pattern kept.
TEST(Transpose8x8, MovesEveryBitToItsTransposedPlace) {
  std::mt19937 rng(81);
  for (int round = 0; round < 100; ++round) {
    alignas(32) uint32_t in[64];
    for (uint32_t& b : in) b = rng();  // every bit pattern: NaNs, -0, denormals included
    float records[65];
    std::memcpy(records + 1, in, sizeof in);  // 4 bytes past a 32-byte boundary at best
    float8 m[8], loaded[8];
    for (int i = 0; i < 8; ++i) m[i] = float8::load_aligned(reinterpret_cast<const float*>(in + 8 * i));
    transpose8x8(m);
    load_transposed8x8(records + 1, loaded);
    for (int j = 0; j < 8; ++j) {
      alignas(32) uint32_t out[8], from_memory[8];
      std::memcpy(out, &m[j], 32);
      std::memcpy(from_memory, &loaded[j], 32);
      for (int i = 0; i < 8; ++i) {
        ASSERT_EQ(out[i], in[8 * i + j]) << "row " << j << " lane " << i;
        ASSERT_EQ(from_memory[i], in[8 * i + j]) << "loaded row " << j << " lane " << i;
      }
    }
  }
}

/// Eight (x, y) pairs, unaligned: lane i of the x row is word 2i, of the y row word 2i + 1.
TEST(LoadPairs8, SplitsEightPairsIntoTwoRows) {
  std::mt19937 rng(85);
  for (int round = 0; round < 100; ++round) {
    uint32_t in[17];
    for (uint32_t& b : in) b = rng();
    float words[17];
    std::memcpy(words, in, sizeof in);
    float8 x, y;
    load_pairs8(words + 1, x, y);
    alignas(32) uint32_t xs[8], ys[8];
    std::memcpy(xs, &x, 32);
    std::memcpy(ys, &y, 32);
    for (int i = 0; i < 8; ++i) {
      ASSERT_EQ(xs[i], in[1 + 2 * i]) << "x lane " << i;
      ASSERT_EQ(ys[i], in[2 + 2 * i]) << "y lane " << i;
    }
  }
}

/// Eight records of 4 and of 5 words (rp::Hit's 20 bytes), in an array sized exactly: lane i of
/// row k is word k of record i, every bit pattern kept.
TEST(LoadRecords4, GivesEachLaneTheFirstFourWordsOfItsRecordAtAnyStride) {
  std::mt19937 rng(83);
  for (size_t stride : {size_t(4), size_t(5), size_t(8)}) {
    for (int round = 0; round < 50; ++round) {
      std::vector<uint32_t> words(7 * stride + 4);
      for (uint32_t& b : words) b = rng();
      float8 out[4];
      load_records4(reinterpret_cast<const float*>(words.data()), out, stride);
      for (int k = 0; k < 4; ++k) {
        alignas(32) uint32_t lanes[8];
        std::memcpy(lanes, &out[k], 32);
        for (size_t l = 0; l < 8; ++l) ASSERT_EQ(lanes[l], words[stride * l + size_t(k)]) << "stride " << stride;
      }
    }
  }
}

/// Records of 3 words, 3 to 6 words apart, in an array that ends with the last record's third
/// word (std::vector sized exactly: nothing readable after it under ASan), indices hitting
/// the first and the last record and repeating some: every lane gets its record's bits.
TEST(GatherRecords3, GivesEachLaneItsRecordsBitsUpToTheLastRecord) {
  std::mt19937 rng(82);
  for (uint32_t count : {1u, 2u, 7u, 100u})
    for (size_t step : {3u, 4u, 6u}) {
      std::vector<uint32_t> words(step * (count - 1) + 3);
      for (uint32_t& b : words) b = rng();  // every bit pattern
      for (int round = 0; round < 200; ++round) {
        alignas(32) int32_t index[8];
        for (int l = 0; l < 8; ++l) index[l] = int32_t(rng() % count);
        index[round % 8] = int32_t(count - 1);
        float8 out[3];
        gather_records3(words.data(), 4 * step, count, index, out);
        for (int k = 0; k < 3; ++k) {
          alignas(32) uint32_t lanes[8];
          std::memcpy(lanes, &out[k], 32);
          for (int l = 0; l < 8; ++l)
            ASSERT_EQ(lanes[l], words[step * size_t(index[l]) + size_t(k)])
                << "count " << count << " stride " << 4 * step << " lane " << l;
        }
      }
    }
}

TEST(Vec3x8, LoadAndLaneKeepEveryBit) {
  Mismatches bad;
  for (const Vec3Case& c : vec3_cases()) {
    const Vec3x8 v = c.a.load();
    const Vec3x8 w(pack(c.a.x), pack(c.a.y), pack(c.a.z));
    for (int i = 0; i < 8; ++i) {
      if (!same_bits(v.lane(i), c.a.lane(i)) || !same_bits(w.lane(i), c.a.lane(i)))
        bad.add("lane " + std::to_string(i) + ": want " + show(c.a.lane(i)) + " got " + show(v.lane(i)) +
                " / " + show(w.lane(i)));
    }
    const Lanes xs = unpack(v.x), ys = unpack(v.y), zs = unpack(v.z);
    for (int i = 0; i < 8; ++i)
      if (bits_of(xs[i]) != bits_of(c.a.x[i]) || bits_of(ys[i]) != bits_of(c.a.y[i]) ||
          bits_of(zs[i]) != bits_of(c.a.z[i]))
        bad.add("component lane " + std::to_string(i) + " of " + show(c.a.lane(i)));
  }
  EXPECT_EQ(bad.count(), 0);
}

TEST(Vec3x8, BroadcastFromVec3fFillsEveryLane) {
  std::mt19937 rng(kSeed + 6);
  for (int i = 0; i < 2000; ++i) {
    const Vec3f v = i % 2 ? Vec3f{random_float(rng), random_float(rng), random_float(rng)}
                          : Vec3f{random_special(rng), random_special(rng), random_special(rng)};
    const Vec3x8 b(v);
    for (int k = 0; k < 8; ++k) EXPECT_TRUE(same_bits(b.lane(k), v)) << show(v) << " lane " << k;
  }
}

TEST(Vec3x8, SubtractMatchesScalarBits) {
  expect_vec3_op(
      "-", [](const Vec3Case& c) { return c.a.load() - c.b.load(); },
      [](const Vec3Case& c, int i) { return c.a.lane(i) - c.b.lane(i); });
}

}  // namespace
}  // namespace rp::simd
