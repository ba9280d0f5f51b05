#include "backends/simd/bvh8_binary_tree.h"

#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <utility>

#include "backends/simd/bvh8_binned_sah.h"
#include "backends/simd/bvh8_collapse.h"
#include "backends/simd/bvh8_costs.h"
#include "backends/simd/bvh8_spatial.h"
#include "base/error.h"

namespace rp::bvh8::build_detail {

namespace {

constexpr uint32_t kMaxSahDepth = 64;  ///< deeper than this, median splits bound the depth

}  // namespace

BinaryTreeBuilder::BinaryTreeBuilder(const CornerSource& corners, RefArray& refs, const BuildOptions& o,
                                     uint32_t first_analytic)
    : corners_(corners),
      refs_(refs),
      opt_(o),
      first_analytic_(first_analytic),
      median_(corners, refs, o, first_analytic) {}

const BuildNode& BinaryTreeBuilder::build() {
  const uint32_t n = uint32_t(refs_.size());
  const BoxPair b = bounds(refs_.data(), 0, n, first_analytic_);
  if (!(opt_.spatial_splits && opt_.rule == SplitRule::sah)) return *build(0, n, 0, b);
  root_area_ = b.box.area();
  BuildNode* root = build_spatial(RefArray(refs_), 0, b, n);
  size_t total = 0;
  for (const RefArray& r : leaf_refs_) total += r.size();
  RP_CHECK(total < kInvalidId, "bvh8: ", total, " references after spatial splits");
  refs_.resize(total);
  place(*root, 0);
  return *root;
}

BuildNode* BinaryTreeBuilder::build(uint32_t begin, uint32_t end, uint32_t depth, const BoxPair& b) {
  BuildNode* node = arenas_.local().make();
  node->begin = begin;
  node->end = end;
  node->left = node->right = nullptr;
  node->box = b.box;
  node->analytic = b.analytic;
  const uint32_t n = end - begin;
  PrimRef* base = refs_.data();
  Split split{begin, {}, {}};  // stays a leaf
  if (n <= 1) {
  } else if (opt_.rule == SplitRule::sah && depth < kMaxSahDepth) {
    if (!(may_leaf(*node, opt_.max_leaf) && n <= kAlwaysLeaf)) {
      const BinnedSplit o = object_split(base, begin, end, b.centroids);
      if (!(may_leaf(*node, opt_.max_leaf) && leaf_cheaper(n, o.cut.sah, b.box)))
        split = apply(base, begin, end, o, b.centroids, first_analytic_);
    }
  } else if (!may_leaf(*node, opt_.max_leaf)) {
    split = halves(base, begin, end, median_.median_split(base, begin, end, node->box), first_analytic_);
  }
  if (const uint32_t mid = split.mid; mid != begin) {
    if (n > kParallelThreshold) {
      tbb::parallel_invoke([&] { node->left = build(begin, mid, depth + 1, split.left); },
                           [&] { node->right = build(mid, end, depth + 1, split.right); });
    } else {
      node->left = build(begin, mid, depth + 1, split.left);
      node->right = build(mid, end, depth + 1, split.right);
    }
  }
  plan(*node, opt_.max_leaf);
  return node;
}

BuildNode* BinaryTreeBuilder::build_spatial(RefArray v, uint32_t depth, const BoxPair& b, size_t budget) {
  BuildNode* node = arenas_.local().make();
  const uint32_t n = uint32_t(v.size());
  node->begin = 0;
  node->end = n;
  node->left = node->right = nullptr;
  node->box = b.box;
  node->analytic = b.analytic;
  RefArray left, right;
  BoxPair lb, rb;
  if (n > 1 && depth < kMaxSahDepth) {
    PrimRef* base = v.data();
    const BinnedSplit o = object_split(base, 0, n, b.centroids);
    BinnedSplit sp;
    if (budget > 0 && !b.analytic && overlap(o) > kMinOverlap * root_area_) sp = spatial_split(corners_, v, b.box);
    if (!(may_leaf(*node, opt_.max_leaf) && leaf_cheaper(n, std::min(o.cut.sah, sp.cut.sah), b.box))) {
      if (sp.cut.sah < o.cut.sah && divide(corners_, v, sp, b.box, left, right) &&
          left.size() + right.size() - n <= budget) {
        lb = bounds(left.data(), 0, uint32_t(left.size()), first_analytic_);
        rb = bounds(right.data(), 0, uint32_t(right.size()), first_analytic_);
      } else {
        left.clear();
        right.clear();
        const Split s = apply(base, 0, n, o, b.centroids, first_analytic_);
        left.assign(v.begin(), v.begin() + s.mid);
        right.assign(v.begin() + s.mid, v.end());
        lb = s.left;
        rb = s.right;
      }
    }
  } else if (n > 1 && !may_leaf(*node, opt_.max_leaf)) {
    const Split s = halves(v.data(), 0, n, median_.median_split(v.data(), 0, n, b.box), first_analytic_);
    left.assign(v.begin(), v.begin() + s.mid);
    right.assign(v.begin() + s.mid, v.end());
    lb = s.left;
    rb = s.right;
  }
  if (left.empty()) {
    const auto at = leaf_refs_.push_back(std::move(v));
    node->begin = uint32_t(at - leaf_refs_.begin());
    node->end = node->begin + n;
  } else {
    v = RefArray();
    const size_t nl = left.size(), nr = right.size(), rest = budget - (nl + nr - n);
    const size_t bl = size_t(double(rest) * double(nl) / double(nl + nr)), br = rest - bl;
    if (n > kParallelThreshold) {
      tbb::parallel_invoke([&] { node->left = build_spatial(std::move(left), depth + 1, lb, bl); },
                           [&] { node->right = build_spatial(std::move(right), depth + 1, rb, br); });
    } else {
      node->left = build_spatial(std::move(left), depth + 1, lb, bl);
      node->right = build_spatial(std::move(right), depth + 1, rb, br);
    }
  }
  plan(*node, opt_.max_leaf);
  return node;
}

uint32_t BinaryTreeBuilder::place(BuildNode& n, uint32_t at) {
  if (n.leaf()) {
    const RefArray& r = leaf_refs_[n.begin];
    std::copy(r.begin(), r.end(), refs_.begin() + at);
    n.begin = at;
    n.end = at + uint32_t(r.size());
    return n.end;
  }
  n.begin = at;
  n.end = place(*n.right, place(*n.left, at));
  return n.end;
}

}  // namespace rp::bvh8::build_detail
