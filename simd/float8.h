#pragma once
/// The 8-wide SIMD vocabulary, pinned to AVX2+FMA. xsimd's default batch is 16 lanes under
/// AVX-512, so every 8-wide type names its architecture explicitly. Include this only from
/// translation units compiled for AVX2+FMA (link rp::avx2, which sets the flags).
///
/// xsimd 8.1 has no batch_bool::mask() and no reduce_min/max; they are added here, once.
/// Functions over lanes take a `mask8 active` last where they have one.

#include <immintrin.h>

#include <bit>
#include <cstdint>
#include <limits>
#include <xsimd/xsimd.hpp>

#include "base/math.h"
#include "simd/prefetch.h"

/// For the small 8-wide routines of a hot loop that GCC would otherwise call out of line once
/// their caller grows (a call passes every Vec3x8 through memory): the leaf decode and the
/// triangle test of the single-ray traversal measurably lost speed that way (figures:
/// docs/notes/2026-11-29-figures-from-code-comments.md).
#define RP_SIMD_INLINE [[gnu::always_inline]] inline

namespace rp::simd {

using Arch = xsimd::fma3<xsimd::avx2>;
using float8 = xsimd::batch<float, Arch>;
using mask8 = xsimd::batch_bool<float, Arch>;
using int8 = xsimd::batch<int32_t, Arch>;  ///< eight 32-bit integers (indices, bit patterns)

static_assert(float8::size == 8, "raypack's packets are 8 rays wide");

/// Bit i set when lane i of m is true (bits 8..31 clear).
inline uint32_t movemask(const mask8& m) { return uint32_t(_mm256_movemask_ps(__m256(m))); }

/// The mask whose lane i is bit i of `bits`.
inline mask8 mask_from_bits(uint32_t bits) {
  const __m256i lane_bit = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
  const __m256i b = _mm256_and_si256(_mm256_set1_epi32(int(bits)), lane_bit);
  return mask8(_mm256_castsi256_ps(_mm256_cmpeq_epi32(b, lane_bit)));
}

/// Lanes whose sign bit is set: negative numbers, -0, -inf (and NaNs with the sign bit).
/// Unlike v < 0 it tells -0 from +0, which the slab test needs (1 / -0 = -inf).
inline mask8 sign_mask(const float8& v) {
  return mask8(_mm256_castsi256_ps(_mm256_srai_epi32(_mm256_castps_si256(v), 31)));
}

/// Lane-wise minimum with the operand order of x86 MINPS: when either lane is NaN the result
/// is the lane of b. The slab test relies on it: min(NaN, x) == x lets a 0 * inf slab
/// (origin on a face of a flat direction) impose no constraint.
inline float8 min_b_on_nan(const float8& a, const float8& b) { return _mm256_min_ps(a, b); }
/// Lane-wise maximum, NaN handled as min_b_on_nan: max(NaN, x) == x.
inline float8 max_b_on_nan(const float8& a, const float8& b) { return _mm256_max_ps(a, b); }

/// Lane-wise maximum and minimum of the bit patterns read as signed 32-bit integers (one-cycle
/// VPMAXSD / VPMINSD where MAXPS / MINPS take four). For floats that are not NaN this is the
/// float order among values >= +0 (and +inf above them); a negative float reads as a negative
/// integer, below every value >= +0, though negatives among themselves come out reversed. So
/// max_bits equals the float max whenever one operand is >= +0, and min_bits equals the float
/// min when both are >= +0 and is negative whenever the float min is (Embree's single-ray
/// node test, "maxi/mini", orders slab distances this way).
inline float8 max_bits(const float8& a, const float8& b) {
  return _mm256_castsi256_ps(_mm256_max_epi32(_mm256_castps_si256(a), _mm256_castps_si256(b)));
}
inline float8 min_bits(const float8& a, const float8& b) {
  return _mm256_castsi256_ps(_mm256_min_epi32(_mm256_castps_si256(a), _mm256_castps_si256(b)));
}
/// Bit i set when lane i of a is above lane i of b, both read as signed 32-bit integers.
inline uint32_t greater_bits(const float8& a, const float8& b) {
  return uint32_t(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpgt_epi32(_mm256_castps_si256(a), _mm256_castps_si256(b)))));
}

/// Smallest lane; NaN lanes are ignored unless every lane is NaN (then NaN). MINPS returns
/// its second operand when either is NaN, so NaN lanes are replaced by +inf before the tree.
inline float reduce_min(const float8& v) {
  const __m256 nan = _mm256_cmp_ps(v, v, _CMP_UNORD_Q);
  if (_mm256_movemask_ps(nan) == 0xff) return std::numeric_limits<float>::quiet_NaN();
  __m256 m = _mm256_blendv_ps(v, _mm256_set1_ps(std::numeric_limits<float>::infinity()), nan);
  m = _mm256_min_ps(_mm256_permute2f128_ps(m, m, 0x01), m);
  m = _mm256_min_ps(_mm256_shuffle_ps(m, m, 0x4e), m);
  m = _mm256_min_ps(_mm256_shuffle_ps(m, m, 0xb1), m);
  return _mm256_cvtss_f32(m);
}

/// Largest lane; NaN lanes are ignored unless every lane is NaN (then NaN).
inline float reduce_max(const float8& v) {
  const __m256 nan = _mm256_cmp_ps(v, v, _CMP_UNORD_Q);
  if (_mm256_movemask_ps(nan) == 0xff) return std::numeric_limits<float>::quiet_NaN();
  __m256 m = _mm256_blendv_ps(v, _mm256_set1_ps(-std::numeric_limits<float>::infinity()), nan);
  m = _mm256_max_ps(_mm256_permute2f128_ps(m, m, 0x01), m);
  m = _mm256_max_ps(_mm256_shuffle_ps(m, m, 0x4e), m);
  m = _mm256_max_ps(_mm256_shuffle_ps(m, m, 0xb1), m);
  return _mm256_cvtss_f32(m);
}

/// Stores m at the 32-byte aligned `lanes` as eight 32-bit integers: -1 for true, 0 for false
/// (the raw lanes, as the tests inspect them; a mask goes to scalar code as movemask bits).
inline void store_mask(int32_t* lanes, const mask8& m) {
  _mm256_store_si256(reinterpret_cast<__m256i*>(lanes), _mm256_castps_si256(__m256(m)));
}

/// N float8 values as scalars, for the few places 8-wide code goes lane by lane and back (a
/// rare scalar fallback, a per-lane callback, rays gathered or hits written one at a time):
/// `lanes[k][l]` is lane l of the k-th value, `load(k)` the k-th value again, with whatever
/// the scalar loop wrote. Constructed from values (stored once) or empty (to be filled).
template <size_t N>
struct Spill {
  alignas(32) float lanes[N][8];

  Spill() = default;
  template <class... V>
    requires(sizeof...(V) == N)
  explicit Spill(const V&... v) {
    size_t k = 0;
    (v.store_aligned(lanes[k++]), ...);
  }
  float8 load(size_t k) const { return float8::load_aligned(lanes[k]); }
};

/// Every bit set in lanes n..7 and clear in lanes 0..n-1 (n = 0..8): what
/// load_unaligned_nan_past ORs into a load to make the lanes past the first n NaN.
inline float8 nan_past(uint32_t n) {
  alignas(32) static constexpr int32_t kOnes[16] = {-1, -1, -1, -1, -1, -1, -1, -1, 0, 0, 0, 0, 0, 0, 0, 0};
  return _mm256_castsi256_ps(~_mm256_loadu_si256(reinterpret_cast<const __m256i*>(kOnes + 8 - n)));
}

/// Eight floats from unaligned `p` with the lanes set in `past` (nan_past(n)) made NaN: the
/// first n floats of a partial block. All 32 bytes are read, so the floats after the first n
/// must be readable; their values are dropped. One OR per load, where a masked load
/// (VMASKMOVPS) is slower.
inline float8 load_unaligned_nan_past(const float* p, const float8& past) {
  return _mm256_or_ps(_mm256_loadu_ps(p), past);
}

/// Eight lane indices into a table of Chunks * 8 floats (Chunks 1..3), read from eight bytes,
/// with the lanes that pick from each chunk after the first worked out once for every
/// table the indices are looked up in (lookup).
template <int Chunks>
struct index8 {
  __m256i i;
  __m256 from[Chunks];  ///< from[c] (c >= 1): lanes whose index is in chunk c or later

  /// The eight unsigned bytes at `p` (any alignment; 8 bytes are read).
  explicit index8(const uint8_t* p) : i(_mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p)))) {
    for (int c = 1; c < Chunks; ++c) from[c] = _mm256_castsi256_ps(_mm256_cmpgt_epi32(i, _mm256_set1_epi32(8 * c - 1)));
  }
};

/// Lane l is table[i[l]] (the table's Chunks * 8 floats must be readable; floats past its
/// real end are never picked by an index inside it): one permute per chunk and a blend for
/// each after the first, no gather and no memory access by index.
template <int Chunks>
RP_SIMD_INLINE float8 lookup(const float* table, const index8<Chunks>& i) {
  __m256 r = _mm256_permutevar8x32_ps(_mm256_loadu_ps(table), i.i);
  for (int c = 1; c < Chunks; ++c)
    r = _mm256_blendv_ps(r, _mm256_permutevar8x32_ps(_mm256_loadu_ps(table + 8 * c), i.i), i.from[c]);
  return r;
}

/// The lane indices that compress_store permutes by, one row of 8 bytes per mask: row m
/// lists the set bits of m from the lowest, then the clear ones.
struct CompressTable {
  alignas(64) uint8_t rows[256][8];
  constexpr CompressTable() : rows() {
    for (int m = 0; m < 256; ++m) {
      int k = 0;
      for (int l = 0; l < 8; ++l)
        if (m >> l & 1) rows[m][k++] = uint8_t(l);
      for (int l = 0; l < 8; ++l)
        if (!(m >> l & 1)) rows[m][k++] = uint8_t(l);
    }
  }
};
inline constexpr CompressTable kCompressTable{};

/// Writes the lanes of `src` (8 integers) picked by `mask` (bits 0..7) to dst[0],
/// dst[1], ... in lane order and returns how many: AVX-512's VPCOMPRESSD, done on AVX2 by
/// one permute from a table and one store. All 8 slots from dst are written: those past the
/// count get the lanes that were not picked, so the caller must own them and overwrite them
/// later if they matter.
inline uint32_t compress_store(const uint32_t* src, uint32_t mask, uint32_t* dst) {
  const __m256i idx = _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(kCompressTable.rows[mask])));
  const __m256i v = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(src));
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(dst), _mm256_permutevar8x32_epi32(v, idx));
  return uint32_t(std::popcount(mask));
}

/// Bit c (c = 0..7) of each of the 8 bytes at `bytes`, as an 8-bit mask (bit l from byte l):
/// which of eight rays' hit masks include child c.
struct ByteBits8 {
  __m256i lanes;
  explicit ByteBits8(const uint8_t* bytes)
      : lanes(_mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(bytes)))) {}
  uint32_t bit(int c) const {
    const __m256i b = _mm256_set1_epi32(1 << c);
    return uint32_t(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(_mm256_and_si256(lanes, b), b))));
  }
};

/// Eight 32-bit counters: lane c counts the masks added with bit c set (how many rays of a
/// stream hit each child of a node).
struct Count8 {
  __m256i n = _mm256_setzero_si256();
  void add(uint32_t bits) { n = _mm256_sub_epi32(n, _mm256_castps_si256(mask_from_bits(bits))); }
  /// The 8 counts at the 32-byte aligned `out`.
  void store(uint32_t* out) const { _mm256_store_si256(reinterpret_cast<__m256i*>(out), n); }
};

/// Number of set bits.
inline int lane_count(uint32_t bits) { return std::popcount(bits); }

/// Lane i of v in every lane (i in 0..7): one permute, no trip through memory.
inline float8 broadcast_lane(const float8& v, int i) {
  return _mm256_permutevar8x32_ps(v, _mm256_set1_epi32(i));
}

/// Transposes the 8x8 matrix whose row i is m[i], in place: afterwards lane i of m[j] is the
/// old lane j of m[i]. Loading eight 32-byte records (eight rays) as rows gives their fields
/// as SoA rows. Bits move unchanged (24 shuffles, no arithmetic).
inline void transpose8x8(float8 m[8]) {
  const __m256 t0 = _mm256_unpacklo_ps(m[0], m[1]), t1 = _mm256_unpackhi_ps(m[0], m[1]);
  const __m256 t2 = _mm256_unpacklo_ps(m[2], m[3]), t3 = _mm256_unpackhi_ps(m[2], m[3]);
  const __m256 t4 = _mm256_unpacklo_ps(m[4], m[5]), t5 = _mm256_unpackhi_ps(m[4], m[5]);
  const __m256 t6 = _mm256_unpacklo_ps(m[6], m[7]), t7 = _mm256_unpackhi_ps(m[6], m[7]);
  const __m256 s0 = _mm256_shuffle_ps(t0, t2, 0x44), s1 = _mm256_shuffle_ps(t0, t2, 0xee);
  const __m256 s2 = _mm256_shuffle_ps(t1, t3, 0x44), s3 = _mm256_shuffle_ps(t1, t3, 0xee);
  const __m256 s4 = _mm256_shuffle_ps(t4, t6, 0x44), s5 = _mm256_shuffle_ps(t4, t6, 0xee);
  const __m256 s6 = _mm256_shuffle_ps(t5, t7, 0x44), s7 = _mm256_shuffle_ps(t5, t7, 0xee);
  m[0] = _mm256_permute2f128_ps(s0, s4, 0x20);
  m[1] = _mm256_permute2f128_ps(s1, s5, 0x20);
  m[2] = _mm256_permute2f128_ps(s2, s6, 0x20);
  m[3] = _mm256_permute2f128_ps(s3, s7, 0x20);
  m[4] = _mm256_permute2f128_ps(s0, s4, 0x31);
  m[5] = _mm256_permute2f128_ps(s1, s5, 0x31);
  m[6] = _mm256_permute2f128_ps(s2, s6, 0x31);
  m[7] = _mm256_permute2f128_ps(s3, s7, 0x31);
}

/// The bits of each lane as an integer, and back.
inline int8 as_int(const float8& v) { return _mm256_castps_si256(v); }
inline float8 as_float(const int8& v) { return _mm256_castsi256_ps(v); }
/// Lanes where the bits of v equal `bits` (as a float mask).
inline mask8 bits_equal(const float8& v, uint32_t bits) {
  return mask8(_mm256_castsi256_ps(_mm256_cmpeq_epi32(as_int(v), _mm256_set1_epi32(int(bits)))));
}
/// Lanes whose bits, read as unsigned integers, are below `bound`.
inline mask8 bits_below(const float8& v, uint32_t bound) {
  const __m256i flip = _mm256_set1_epi32(int(0x80000000u));  // unsigned order through signed compare
  return mask8(_mm256_castsi256_ps(_mm256_cmpgt_epi32(_mm256_xor_si256(_mm256_set1_epi32(int(bound)), flip),
                                                      _mm256_xor_si256(as_int(v), flip))));
}
/// Lane l is base[index[l]] (VPGATHERDD / VGATHERDPS; every index must be readable).
inline float8 gather(const float* base, const int8& index) { return _mm256_i32gather_ps(base, index, 4); }
inline int8 gather(const int32_t* base, const int8& index) { return _mm256_i32gather_epi32(base, index, 4); }

/// The first 4 floats of eight records `stride` floats apart (>= 4; unaligned) as 4 rows: lane
/// i of out[k] is float k of record i. Bits move unchanged. (Stride 5: rp::Hit, whose first
/// 16 bytes are t, prim_id, u, v.)
inline void load_records4(const float* records, float8 out[4], size_t stride = 4) {
  __m256 r[4];  // r[j] holds records j and j + 4
  for (size_t j = 0; j < 4; ++j)
    r[j] = _mm256_set_m128(_mm_loadu_ps(records + stride * (j + 4)), _mm_loadu_ps(records + stride * j));
  const __m256 t0 = _mm256_unpacklo_ps(r[0], r[1]), t1 = _mm256_unpackhi_ps(r[0], r[1]);
  const __m256 t2 = _mm256_unpacklo_ps(r[2], r[3]), t3 = _mm256_unpackhi_ps(r[2], r[3]);
  out[0] = _mm256_shuffle_ps(t0, t2, 0x44);
  out[1] = _mm256_shuffle_ps(t0, t2, 0xee);
  out[2] = _mm256_shuffle_ps(t1, t3, 0x44);
  out[3] = _mm256_shuffle_ps(t1, t3, 0xee);
}

/// Eight (x, y) pairs of floats at p (16 floats, unaligned) as a row of the x and a row of the
/// y: lane i of x is p[2i], of y p[2i + 1]. Bits move unchanged.
inline void load_pairs8(const float* p, float8& x, float8& y) {
  const __m256 a = _mm256_loadu_ps(p), b = _mm256_loadu_ps(p + 8);
  const __m256 even = _mm256_shuffle_ps(a, b, 0x88), odd = _mm256_shuffle_ps(a, b, 0xdd);  // x0 x1 x4 x5 | x2 x3 x6 x7
  x = _mm256_castpd_ps(_mm256_permute4x64_pd(_mm256_castps_pd(even), 0xd8));
  y = _mm256_castpd_ps(_mm256_permute4x64_pd(_mm256_castps_pd(odd), 0xd8));
}

/// Eight consecutive 32-byte records (8 floats each, unaligned) as 8 rows: lane i of out[k] is
/// float k of record i (eight rays' fields as SoA rows). Two load_records4, each record read
/// as two 16-byte halves straight into the shuffles: loading the records as whole rows into
/// an array first made GCC copy them through the stack 16 bytes at a time and read them back
/// 32 at a time, which no store can forward.
inline void load_transposed8x8(const float* records, float8 out[8]) {
  load_records4(records, out, 8);
  load_records4(records + 4, out + 4, 8);
}

/// Records of 3 floats (or 3 words: bits move unchanged), `count` of them `stride` bytes
/// apart from `base` (stride >= 12, a multiple of 4): lane l of out[k] is float k of record
/// index[l]. Each record is read as 16 bytes (its 12 and at most the next record's first 4),
/// the last one of the array as 12, and the 8 transposed: a third of the instructions of 3
/// gathers, which wait on one load per lane each.
inline void gather_records3(const void* base, size_t stride, size_t count, const int32_t index[8], float8 out[3]) {
  auto record = [&](int32_t i) {
    const float* p = reinterpret_cast<const float*>(static_cast<const char*>(base) + stride * uint32_t(i));
    return size_t(uint32_t(i)) + 1 < count ? _mm_loadu_ps(p) : _mm_setr_ps(p[0], p[1], p[2], 0.0f);
  };
  __m256 r[4];  // r[j] holds records index[j] and index[j + 4]
  for (int j = 0; j < 4; ++j) r[j] = _mm256_set_m128(record(index[j + 4]), record(index[j]));
  const __m256 t0 = _mm256_unpacklo_ps(r[0], r[1]), t1 = _mm256_unpackhi_ps(r[0], r[1]);
  const __m256 t2 = _mm256_unpacklo_ps(r[2], r[3]), t3 = _mm256_unpackhi_ps(r[2], r[3]);
  out[0] = _mm256_shuffle_ps(t0, t2, 0x44);
  out[1] = _mm256_shuffle_ps(t0, t2, 0xee);
  out[2] = _mm256_shuffle_ps(t1, t3, 0x44);
}

/// The inverse of load_records4: 4 rows as 8 records of 4 floats at 32-byte aligned `records`.
inline void store_records4(const float8 in[4], float* records) {
  const __m256 t0 = _mm256_unpacklo_ps(in[0], in[1]), t1 = _mm256_unpackhi_ps(in[0], in[1]);
  const __m256 t2 = _mm256_unpacklo_ps(in[2], in[3]), t3 = _mm256_unpackhi_ps(in[2], in[3]);
  const __m256 r0 = _mm256_shuffle_ps(t0, t2, 0x44), r1 = _mm256_shuffle_ps(t0, t2, 0xee);
  const __m256 r2 = _mm256_shuffle_ps(t1, t3, 0x44), r3 = _mm256_shuffle_ps(t1, t3, 0xee);
  // r[j] holds records j (low half) and j + 4 (high half)
  const __m256 r[4] = {r0, r1, r2, r3};
  for (int j = 0; j < 4; ++j) {
    _mm_store_ps(records + 4 * j, _mm256_castps256_ps128(r[j]));
    _mm_store_ps(records + 4 * (j + 4), _mm256_extractf128_ps(r[j], 1));
  }
}

/// Three 8-wide components: eight 3-vectors in SoA.
struct Vec3x8 {
  float8 x, y, z;

  Vec3x8() = default;
  Vec3x8(const float8& x_, const float8& y_, const float8& z_) : x(x_), y(y_), z(z_) {}
  /// All lanes = v.
  explicit Vec3x8(const Vec3f& v) : x(v.x), y(v.y), z(v.z) {}
  /// Lanes from three aligned SoA arrays of 8 floats.
  static Vec3x8 load(const float* xs, const float* ys, const float* zs) {
    return {float8::load_aligned(xs), float8::load_aligned(ys), float8::load_aligned(zs)};
  }
  /// Lane i in every lane.
  Vec3x8 broadcast(int i) const {
    return {simd::broadcast_lane(x, i), simd::broadcast_lane(y, i), simd::broadcast_lane(z, i)};
  }
  /// Lane i as a scalar vector.
  Vec3f lane(int i) const {
    alignas(32) float a[8], b[8], c[8];
    x.store_aligned(a);
    y.store_aligned(b);
    z.store_aligned(c);
    return {a[i], b[i], c[i]};
  }
};

inline Vec3x8 operator-(const Vec3x8& a, const Vec3x8& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }

/// Cross product with one FMA per component, in the order of rp::cross_fma (and Embree's
/// Vec3 cross): fms(a.y, b.z, a.z * b.y), ...
inline Vec3x8 cross_fma(const Vec3x8& a, const Vec3x8& b) {
  return {xsimd::fms(a.y, b.z, a.z * b.y), xsimd::fms(a.z, b.x, a.x * b.z), xsimd::fms(a.x, b.y, a.y * b.x)};
}

/// Max-abs norm of each lane.
inline float8 max_abs(const Vec3x8& a) {
  return xsimd::max(xsimd::abs(a.x), xsimd::max(xsimd::abs(a.y), xsimd::abs(a.z)));
}

/// Dot product with two FMAs, in the order of rp::dot_fma: fma(a.x, b.x, fma(a.y, b.y, a.z * b.z)).
inline float8 dot_fma(const Vec3x8& a, const Vec3x8& b) {
  return xsimd::fma(a.x, b.x, xsimd::fma(a.y, b.y, a.z * b.z));
}

}  // namespace rp::simd
