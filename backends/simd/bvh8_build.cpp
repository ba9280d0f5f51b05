#include <algorithm>
#include <chrono>
#include <cmath>
#include <utility>
#include <vector>

#include "backends/simd/bvh8.h"
#include "backends/simd/bvh8_binary_tree.h"
#include "backends/simd/bvh8_collapse.h"
#include "backends/simd/bvh8_costs.h"
#include "backends/simd/bvh8_leaves.h"
#include "backends/simd/bvh8_refs.h"
#include "base/error.h"

namespace rp::bvh8 {

using namespace build_detail;

double build_detail::sah_cost(const Bvh8& t) {
  const double root = t.bounds.area();
  if (t.empty() || !(root > 0)) return 0;
  double cost = 1.0;  // the root
  for (const Bvh8Node& n : t.nodes)
    for (int k = 0; k < 8 && n.child[k] != kEmpty; ++k) {
      const Box3f b({n.lo_x[k], n.lo_y[k], n.lo_z[k]}, {n.hi_x[k], n.hi_y[k], n.hi_z[k]});
      if (is_leaf(n.child[k])) {
        cost += b.area() / root * (kLeafCost + kPrimCost * double(t.leaf(n.child[k]).n));
      } else {
        cost += b.area() / root * kTraversalCost;
      }
    }
  return cost;
}

namespace {

/// Appends to `ids` the prim_ids of the refs in [at, at + n) that triangle_refs marked
/// zero-area; refs[at] is triangle `first_id`.
void zero_area_ids(const RefArray& refs, uint32_t at, uint32_t n, uint32_t first_id, std::vector<uint32_t>& ids) {
  for (uint32_t i = at; i < at + n; ++i)
    if (refs[i].prim_id == kInvalidId) ids.push_back(first_id + (i - at));
}

/// The tree over `refs` (the primitives of `what`, ids in the scene's numbering), timed from
/// `start`.
Bvh8 build_refs(const Scene& scene, RefArray refs, const BuildOptions& options, const Selection& what,
                std::chrono::steady_clock::time_point start) {
  const uint32_t first_analytic = scene.sphere_base();
  Bvh8 out;
  out.stats.prims = uint32_t(refs.size());
  if (!refs.empty()) {
    const bool spatial = options.spatial_splits && options.rule == SplitRule::sah;
    const CornerSource corners(scene, spatial, what);
    BinaryTreeBuilder builder(corners, refs, options, first_analytic);
    const BuildNode& root = builder.build();
    out.bounds = root.box;
    std::vector<PlacedLeaf> leaves = collapse(root, out);
    write_leaves(corners, refs, spatial, leaves, out);
  }
  out.first_analytic = first_analytic;
  out.has_analytic = what.mesh == Selection::kWorld && scene.plane_base() > scene.sphere_base();
  out.stats.nodes = uint32_t(out.nodes.size());
  out.stats.built_sah_cost = out.stats.sah_cost = sah_cost(out);
  out.stats.bytes = out.nodes.size() * sizeof(Bvh8Node) + out.leaf_data.size() * sizeof(float);
  out.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace

Bvh8 build(const Scene& scene, const BuildOptions& options) {
  RP_CHECK(options.max_leaf >= 1 && options.max_leaf <= 8, "bvh8: max_leaf ", options.max_leaf,
           " must be in 1..8");
  const auto start = std::chrono::steady_clock::now();
  // References in parallel (the array's pages first touched there), then the zero-area
  // triangles and the instanced meshes' (which are not in the world), marked kInvalidId,
  // dropped in order.
  RefArray refs(scene.plane_base());  // triangles, then spheres, quadrics and polygons
  size_t instanced = 0, zero_area = 0;
  for (size_t m = 0; m < scene.meshes().size(); ++m) {
    if (scene.is_instanced(m)) {
      const uint32_t base = scene.mesh_base(m), n = scene.meshes()[m].triangle_count();
      for (uint32_t t = 0; t < n; ++t) refs[base + t].prim_id = kInvalidId;
      instanced += n;
    } else {
      zero_area += triangle_refs(scene, m, refs, scene.mesh_base(m));
    }
  }
  for (uint32_t id = scene.sphere_base(); id < scene.plane_base(); ++id) refs[id] = PrimRef::make(scene.prim_bounds(id), id);
  std::vector<uint32_t> left_out;
  if (zero_area > 0)
    for (size_t m = 0; m < scene.meshes().size(); ++m)
      if (!scene.is_instanced(m))
        zero_area_ids(refs, scene.mesh_base(m), scene.meshes()[m].triangle_count(), scene.mesh_base(m), left_out);
  if (instanced + zero_area > 0) drop_invalid(refs);
  Bvh8 out = build_refs(scene, std::move(refs), options, Selection{}, start);
  out.zero_area = std::move(left_out);
  return out;
}

Bvh8 build_mesh(const Scene& scene, uint32_t mesh, const BuildOptions& options) {
  RP_CHECK(options.max_leaf >= 1 && options.max_leaf <= 8, "bvh8: max_leaf ", options.max_leaf,
           " must be in 1..8");
  RP_CHECK(mesh < scene.meshes().size(), "bvh8: mesh ", mesh, " out of range");
  const auto start = std::chrono::steady_clock::now();
  RefArray refs(scene.meshes()[mesh].triangle_count());
  std::vector<uint32_t> left_out;
  if (triangle_refs(scene, mesh, refs, 0) > 0) {
    zero_area_ids(refs, 0, uint32_t(refs.size()), scene.mesh_base(mesh), left_out);
    drop_invalid(refs);
  }
  Bvh8 out = build_refs(scene, std::move(refs), options, Selection{mesh}, start);
  out.zero_area = std::move(left_out);
  return out;
}

float mean_leaf_size(const Bvh8& bvh) {
  double area = 0.0;
  size_t leaves = 0;
  for (const Bvh8Node& n : bvh.nodes)
    for (int c = 0; c < 8 && n.child[c] != kEmpty; ++c) {
      if (!is_leaf(n.child[c])) continue;
      const double dx = double(n.hi_x[c]) - n.lo_x[c], dy = double(n.hi_y[c]) - n.lo_y[c],
                   dz = double(n.hi_z[c]) - n.lo_z[c];
      area += 2.0 * (dx * dy + dy * dz + dz * dx);
      ++leaves;
    }
  return leaves ? float(std::sqrt(area / double(leaves) / 6.0)) : 0.0f;
}

InstanceTree build_instances(const Scene& scene) {
  const auto start = std::chrono::steady_clock::now();
  InstanceTree out;
  RefArray refs;
  for (uint32_t i = 0; i < scene.instances().size(); ++i) {
    const Instance& in = scene.instances()[i];
    if (in.bounds.empty()) continue;  // a mesh without triangles
    // Grown by 2^-16 of the box's size and place, times the transform's condition: the
    // object-space ray is rounded (rp::object_ray), and a hit it finds must not lie outside
    // the box a traversal culls by (see InstanceTree).
    const Affine3d w(in.world_to_object), m(in.object_to_world);
    const double cond = m.linear_norm() * w.linear_norm();
    const Box3d b(Vec3d(in.bounds.lo), Vec3d(in.bounds.hi));
    const double size = max_component(b.extent()) + std::max(max_component(abs(b.lo)), max_component(abs(b.hi)));
    refs.push_back(PrimRef::make(outward(b, 0x1p-16 * cond * size), i));
  }
  out.stats.prims = uint32_t(refs.size());
  if (!refs.empty()) {
    // Every instance a leaf of its own (all refs "analytic" to the builder), by SAH.
    const BuildOptions one{.rule = SplitRule::sah, .max_leaf = 1, .spatial_splits = false};
    const CornerSource corners(scene, false, Selection{});
    BinaryTreeBuilder builder(corners, refs, one, 0);
    const BuildNode& root = builder.build();
    out.bounds = root.box;
    Bvh8 tree;
    const std::vector<PlacedLeaf> leaves = collapse(root, tree);
    point_at_refs(refs, leaves, tree);
    out.nodes = std::move(tree.nodes);
    out.stats.depth = tree.stats.depth;
    out.stats.leaves = tree.stats.leaves;
  }
  out.stats.nodes = uint32_t(out.nodes.size());
  out.stats.bytes = out.nodes.size() * sizeof(Bvh8Node);
  out.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace rp::bvh8
