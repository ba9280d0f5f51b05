#include "backends/simd/bvh8_leaves.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstring>
#include <span>

#include "base/error.h"

namespace rp::bvh8::build_detail {

namespace {

/// The vertex block of a leaf: each distinct corner (by its bits, NaN included) numbered in
/// first-seen order; `of[c]` is corner c's number, `v` how many there are.
struct CornerIndex {
  uint32_t v = 0;
  uint8_t of[3 * 8];
};

/// Finds each corner's vertex through a 32-slot hash table of the vertices seen so far (a
/// leaf has at most 24), probing on from the hashed slot past occupied slots whose vertex
/// differs. A match and a new vertex then take the same instructions: the linear search
/// this replaced branched on where its match lay, a guess that failed about once per
/// corner (measured slower; figures: docs/notes/2026-11-29-figures-from-code-comments.md).
CornerIndex index_corners(std::span<const Vec3f> corners) {
  constexpr uint32_t kSlots = 32, kFree = 0xff;
  static_assert(kSlots > kMaxLeafVertices);
  CornerIndex ci;
  uint32_t bits[3 * 8][3];  // each corner's coordinates as integers
  uint32_t first[3 * 8];    // first[i]: the corner that vertex i was first seen as
  uint8_t slot_of[kSlots];
  std::memcpy(bits, corners.data(), corners.size() * sizeof(Vec3f));
  std::memset(slot_of, kFree, sizeof(slot_of));
  for (size_t c = 0; c < corners.size(); ++c) {
    const uint32_t* k = bits[c];
    uint32_t slot = ((k[0] * 0x9E3779B1u) ^ (k[1] * 0x85EBCA77u) ^ (k[2] * 0xC2B2AE3Du)) >> 27;
    for (;;) {
      const uint32_t i = slot_of[slot];
      if (i == kFree) break;
      const uint32_t* o = bits[first[i]];
      if (((k[0] ^ o[0]) | (k[1] ^ o[1]) | (k[2] ^ o[2])) == 0) break;
      slot = (slot + 1) % kSlots;
    }
    const bool seen = slot_of[slot] != kFree;
    const uint32_t i = seen ? slot_of[slot] : ci.v;
    first[ci.v] = uint32_t(c);  // kept only when the vertex is new
    ci.v += !seen;
    slot_of[slot] = uint8_t(i);
    ci.of[c] = uint8_t(i);
  }
  return ci;
}

/// Writes the leaf of the primitives `ids` with these corners and their index (see Leaf):
/// leaf_words(n, index.v) floats at `out`.
void store_leaf(float* out, std::span<const Vec3f> corners, std::span<const uint32_t> ids, const CornerIndex& index) {
  const uint32_t n = uint32_t(ids.size()), v = index.v;
  std::fill_n(out, leaf_words(n, v), 0.0f);
  uint8_t* bytes = reinterpret_cast<uint8_t*>(out);
  bytes[0] = uint8_t((n - 1) | (v - 1) << 3);
  for (uint32_t k = 0; k < n; ++k)
    for (uint32_t j = 0; j < 3; ++j) bytes[1 + j * n + k] = index.of[3 * k + j];
  const uint32_t ids_at = (3 * n + 4) / 4;
  for (uint32_t k = 0; k < n; ++k) out[ids_at + k] = std::bit_cast<float>(ids[k]);
  float* x = out + ids_at + n;
  for (size_t c = 0; c < corners.size(); ++c) {  // a shared vertex is written once per corner, the same bits
    const uint32_t i = index.of[c];
    x[i] = corners[c].x;
    x[v + i] = corners[c].y;
    x[2 * v + i] = corners[c].z;
  }
}

/// Writes the leaves of one tree (write_leaves).
class LeafWriter {
 public:
  LeafWriter(const CornerSource& corners, RefArray& refs, bool repeats, std::vector<PlacedLeaf>& leaves, Bvh8& out)
      : corners_(corners), refs_(refs), out_(out), repeats_(repeats), leaves_(leaves) {}

  void fill() {
    const size_t leaves = leaves_.size(), chunks = (leaves + kChunk - 1) / kChunk;
    std::vector<std::vector<float>> made(chunks);
    tbb::parallel_for(size_t(0), chunks,
                      [&](size_t c) { made[c] = make_chunk(c * kChunk, std::min(leaves, (c + 1) * kChunk)); });
    std::vector<size_t> base(chunks + 1, 0);
    for (size_t c = 0; c < chunks; ++c) base[c + 1] = base[c] + made[c].size();
    RP_CHECK(base[chunks] <= kMaxLeafOffset, "bvh8: the leaves need more than ", uint64_t(kMaxLeafOffset) * 4,
             " bytes");
    out_.leaf_data.resize(base[chunks] + kLeafPad);
    std::fill_n(out_.leaf_data.end() - kLeafPad, kLeafPad, 0.0f);
    tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
      std::copy(made[c].begin(), made[c].end(), out_.leaf_data.begin() + ptrdiff_t(base[c]));
      for (size_t i = c * kChunk; i < std::min(leaves, (c + 1) * kChunk); ++i) leaves_[i].offset += uint32_t(base[c]);
      std::vector<float>().swap(made[c]);
    });
    tbb::parallel_for(tbb::blocked_range<size_t>(0, out_.nodes.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i < r.end(); ++i)
        for (int32_t& c : out_.nodes[i].child)
          if (is_leaf(c)) c = leaf_ref(leaves_[leaf_offset(c)].offset);
    });
  }

 private:
  /// Leaves made by one task (fill): about 17 KB of leaf words, whose corners (37 KB)
  /// stay in L1 and L2 between the gather and the writes.
  static constexpr size_t kChunk = 128;

  /// The words of leaves [first, last) back to back; each leaf's offset among them set.
  std::vector<float> make_chunk(size_t first, size_t last) {
    uint32_t ids[kChunk * 8];
    Vec3f corners[kChunk * 8 * 3];
    size_t n = 0;
    for (size_t i = first; i < last; ++i) {
      PlacedLeaf& leaf = leaves_[i];
      if (repeats_) drop_repeats(leaf);
      for (uint32_t k = 0; k < leaf.count; ++k) ids[n++] = refs_[leaf.ref + k].prim_id;
    }
    corners_.gather(std::span(ids, n), corners);
    std::vector<float> words;
    words.reserve(n * 6 + (last - first) * 8);  // about 5.8 words per primitive, 3 per vertex
    n = 0;
    for (size_t i = first; i < last; ++i) {
      PlacedLeaf& leaf = leaves_[i];
      const std::span<const Vec3f> c(corners + 3 * n, 3 * size_t(leaf.count));
      const CornerIndex index = index_corners(c);
      leaf.offset = uint32_t(words.size());
      words.resize(words.size() + leaf_words(leaf.count, index.v));
      store_leaf(words.data() + leaf.offset, c, std::span(ids + n, leaf.count), index);
      n += leaf.count;
    }
    return words;
  }

  /// Keeps the first ref of each primitive in the leaf's range (with spatial splits, pieces of
  /// one triangle can meet again in a leaf that took a whole subtree). The plan allows at
  /// most max_leaf refs where the subtree began, and every piece below comes from one of
  /// those, so at most max_leaf primitives remain.
  void drop_repeats(PlacedLeaf& leaf) {
    uint32_t kept = 0;
    for (uint32_t k = 0; k < leaf.count; ++k) {
      const PrimRef r = refs_[leaf.ref + k];
      bool seen = false;
      for (uint32_t j = 0; j < kept; ++j) seen |= refs_[leaf.ref + j].prim_id == r.prim_id;
      if (!seen) refs_[leaf.ref + kept++] = r;
    }
    RP_CHECK(kept <= 8, "bvh8: a leaf of ", kept, " primitives");
    leaf.count = kept;
  }

  const CornerSource& corners_;
  RefArray& refs_;
  Bvh8& out_;
  bool repeats_;
  std::vector<PlacedLeaf>& leaves_;  ///< numbered by the collapse; their offsets (words) by fill
};

}  // namespace

void write_leaves(const CornerSource& corners, RefArray& refs, bool repeats, std::vector<PlacedLeaf>& leaves,
                  Bvh8& out) {
  LeafWriter(corners, refs, repeats, leaves, out).fill();
}

void point_at_refs(const RefArray& refs, const std::vector<PlacedLeaf>& leaves, Bvh8& out) {
  for (Bvh8Node& n : out.nodes)
    for (int32_t& c : n.child)
      if (is_leaf(c)) {
        const PlacedLeaf& leaf = leaves[leaf_offset(c)];
        RP_CHECK(leaf.count == 1, "bvh8: an instance leaf of ", leaf.count, " refs");
        c = leaf_ref(refs[leaf.ref].prim_id);
      }
}

}  // namespace rp::bvh8::build_detail

namespace rp::bvh8 {

uint32_t write_leaf(float* out, std::span<const Vec3f> corners, std::span<const uint32_t> ids) {
  RP_CHECK(ids.size() >= 1 && ids.size() <= 8 && corners.size() == 3 * ids.size(), "bvh8: a leaf of ", ids.size(),
           " primitives and ", corners.size(), " corners");
  const build_detail::CornerIndex index = build_detail::index_corners(corners);
  build_detail::store_leaf(out, corners, ids, index);
  return index.v;
}

}  // namespace rp::bvh8
