#include "backends/simd/bvh8_collapse.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <limits>

#include "backends/simd/bvh8_costs.h"
#include "base/error.h"

namespace rp::bvh8::build_detail {

void plan(BuildNode& n, uint32_t max_leaf) {
  constexpr float inf = std::numeric_limits<float>::infinity();
  const float area = n.box.area();
  const float leaf = may_leaf(n, max_leaf) ? area * (kLeafCost + kPrimCost * float(n.count())) : inf;
  std::fill_n(n.split, 8, uint8_t(0));
  if (n.leaf()) {
    n.as_leaf = true;
    std::fill_n(n.cost, 8, leaf);
    return;
  }
  const BuildNode &l = *n.left, &r = *n.right;
  float dist[9];  // dist[j]: the subtree as j children (j = 2..8), at[j] of them from the left
  uint8_t at[9] = {};
  for (int j = 2; j <= 8; ++j) {
    dist[j] = inf;
    for (int k = 1; k < j; ++k) {
      const float c = l.cost[k - 1] + r.cost[j - k - 1];
      if (c < dist[j]) {
        dist[j] = c;
        at[j] = uint8_t(k);
      }
    }
  }
  int width = 2;
  for (int j = 3; j <= 8; ++j)
    if (dist[j] < dist[width]) width = j;
  const float inner = area * kTraversalCost + dist[width];
  n.node_width = uint8_t(width);
  n.node_split = at[width];
  n.as_leaf = leaf <= inner;
  n.cost[0] = std::min(leaf, inner);
  for (int i = 2; i <= 8; ++i) {
    if (dist[i] < n.cost[i - 2]) {
      n.cost[i - 1] = dist[i];
      n.split[i - 1] = at[i];
    } else {
      n.cost[i - 1] = n.cost[i - 2];
    }
  }
}

namespace {

/// collapse() for one tree: the layout's cursor and its leaves.
class Collapser {
 public:
  explicit Collapser(Bvh8& out) : out_(out) {}

  void root(const BuildNode& bn) {
    out_.nodes.resize(1);
    clear(out_.nodes[0]);
    if (bn.as_leaf) {  // a one-leaf tree still needs a root node
      leaves_.resize(1);
      set_child(0, 0, bn, place_leaf(bn, 0));
      out_.stats.depth = 1;
      out_.stats.leaves = 1;
      return;
    }
    std::vector<Subtree> subtrees;
    Cursor top{1, 0, 0};
    lay_out(0, bn, 1, top, &subtrees);
    out_.nodes.resize(top.node);
    leaves_.resize(top.leaf);
    tbb::parallel_for(size_t(0), subtrees.size(), [&](size_t i) { subtrees[i].size = count(*subtrees[i].bn); });
    Cursor next = top;
    for (Subtree& t : subtrees) {
      t.at = {next.node, next.leaf, 0};
      next.node += t.size.nodes;
      next.leaf += t.size.leaves;
    }
    RP_CHECK(next.leaf <= kMaxLeafOffset, "bvh8: more than ", kMaxLeafOffset, " leaves");
    out_.nodes.resize(next.node);
    leaves_.resize(next.leaf);
    tbb::parallel_for(size_t(0), subtrees.size(), [&](size_t i) {
      Subtree& t = subtrees[i];
      const size_t index = t.at.node++;
      clear(out_.nodes[index]);
      set_child(t.parent, t.slot, *t.bn, int32_t(index));
      lay_out(index, *t.bn, t.depth, t.at, nullptr);
    });
    uint32_t depth = top.depth;
    for (const Subtree& t : subtrees) depth = std::max(depth, t.at.depth);
    out_.stats.depth = depth;
    out_.stats.leaves = uint32_t(next.leaf);
  }

  std::vector<PlacedLeaf>& leaves() { return leaves_; }

 private:
  /// Subtrees of fewer refs are laid out by one task each.
  static constexpr uint32_t kSubtree = 4096;

  /// The next free node and leaf numbers, and the deepest level laid out.
  struct Cursor {
    size_t node, leaf;
    uint32_t depth;
  };
  /// 8-wide nodes and leaves of the layout of an inner `bn` (itself included).
  struct Counts {
    size_t nodes = 0, leaves = 0;
  };
  /// An inner child left by the top of the layout: where its node goes (parent, slot), its
  /// level, size and, once counted, its places.
  struct Subtree {
    size_t parent;
    int slot;
    const BuildNode* bn;
    uint32_t depth;
    Counts size;
    Cursor at;
  };

  static void clear(Bvh8Node& n) {
    constexpr float inf = std::numeric_limits<float>::infinity();
    for (int i = 0; i < 8; ++i) {
      n.lo_x[i] = n.lo_y[i] = n.lo_z[i] = inf;
      n.hi_x[i] = n.hi_y[i] = n.hi_z[i] = -inf;
      n.child[i] = kEmpty;
    }
  }

  void set_child(size_t node, int slot, const BuildNode& c, int32_t ref) {
    Bvh8Node& n = out_.nodes[node];
    n.lo_x[slot] = c.box.lo.x;
    n.lo_y[slot] = c.box.lo.y;
    n.lo_z[slot] = c.box.lo.z;
    n.hi_x[slot] = c.box.hi.x;
    n.hi_y[slot] = c.box.hi.y;
    n.hi_z[slot] = c.box.hi.z;
    n.child[slot] = ref;
  }

  /// Appends the pieces of `bn` at out[size] when its subtree takes at most i children of a
  /// node.
  static void gather(const BuildNode& bn, int i, const BuildNode** out, int& size) {
    while (i > 1 && bn.split[i - 1] == 0) --i;
    if (i == 1) {
      out[size++] = &bn;
      return;
    }
    gather(*bn.left, bn.split[i - 1], out, size);
    gather(*bn.right, i - bn.split[i - 1], out, size);
  }
  /// The children of the 8-wide node an inner `bn` becomes; returns how many (2..8).
  static int children(const BuildNode& bn, const BuildNode** kids) {
    int size = 0;
    gather(*bn.left, bn.node_split, kids, size);
    gather(*bn.right, bn.node_width - bn.node_split, kids, size);
    return size;
  }

  /// Counts of the layout of an inner `bn`.
  static Counts count(const BuildNode& bn) {
    const BuildNode* kids[8];
    const int size = children(bn, kids);
    Counts c{1, 0};
    for (int k = 0; k < size; ++k) {
      if (kids[k]->as_leaf) {
        ++c.leaves;
      } else {
        const Counts below = count(*kids[k]);
        c.nodes += below.nodes;
        c.leaves += below.leaves;
      }
    }
    return c;
  }

  /// Fills node `index` with the children of an inner `bn` (as_leaf false), as the plan cut
  /// them, then descends, taking node and leaf numbers from `at`. A node's leaves are
  /// numbered one after another, and its inner children's nodes are placed together (as
  /// Embree allocates a node's children): what one ray visits next is often adjacent in
  /// memory. With `defer` (the top of the layout) the arrays grow as it goes, and an inner
  /// child of fewer than kSubtree refs is left to `defer` instead of descended into.
  void lay_out(size_t index, const BuildNode& bn, uint32_t depth, Cursor& at, std::vector<Subtree>* defer) {
    at.depth = std::max(at.depth, depth);
    const BuildNode* kids[8];
    const int size = children(bn, kids);
    if (defer) leaves_.resize(at.leaf + size_t(size));
    int inner[8], inners = 0;
    for (int c = 0; c < size; ++c) {
      if (kids[c]->as_leaf) {
        set_child(index, c, *kids[c], place_leaf(*kids[c], at.leaf++));
      } else if (defer && kids[c]->count() < kSubtree) {
        defer->push_back({index, c, kids[c], depth + 1, {}, {}});
      } else {
        inner[inners++] = c;
      }
    }
    const size_t first = at.node;
    at.node += size_t(inners);
    if (defer) out_.nodes.resize(at.node);
    for (int i = 0; i < inners; ++i) {
      clear(out_.nodes[first + i]);
      set_child(index, inner[i], *kids[inner[i]], int32_t(first + i));
    }
    for (int i = 0; i < inners; ++i) lay_out(first + i, *kids[inner[i]], depth + 1, at, defer);
  }

  /// Records leaf number `index`; its place in leaf_data is known once every leaf's size is
  /// (write_leaves), so until then the node holds the leaf's number where its offset will go.
  int32_t place_leaf(const BuildNode& bn, size_t index) {
    leaves_[index] = {bn.begin, bn.end - bn.begin, 0};
    return leaf_ref(uint32_t(index));
  }

  Bvh8& out_;
  std::vector<PlacedLeaf> leaves_;  ///< numbered by lay_out; their offsets (words) by write_leaves
};

}  // namespace

std::vector<PlacedLeaf> collapse(const BuildNode& root, Bvh8& out) {
  Collapser collapser(out);
  collapser.root(root);
  return std::move(collapser.leaves());
}

}  // namespace rp::bvh8::build_detail
