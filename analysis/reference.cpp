// The reference's build, its one tree walk and every query over it (the closest hit, every
// hit, the closest point), in one file of over 600 lines: the walks are nested types of
// Reference that read its private tree layout, which no other file sees.

#include "analysis/reference.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <tuple>
#include <unordered_map>

#include "base/bbox.h"
#include "base/error.h"
#include "core/backend.h"
#include "core/geometry/closest_point.h"
#include "core/geometry/intersection.h"
#include "core/geometry/plane.h"
#include "core/geometry/sphere.h"
#include "core/geometry/triangle.h"
#include "core/scene.h"

namespace rp {

namespace {

constexpr size_t kLeafSize = 4;
/// Subtrees with more primitives than this are built as parallel TBB tasks.
constexpr size_t kParallelBuild = 8192;
/// Median split halves the primitive count per level: depth <= ceil(log2(2^32 / 4)) + 1.
constexpr int kStackSize = 64;
constexpr double kFloatMax = double(std::numeric_limits<float>::max());

double max_abs(const Vec3d& v) { return max_component(abs(v)); }

/// Nodes of the subtree over n primitives; the tree shape depends on n alone (median split),
/// which lets every subtree be built in parallel straight into its depth-first slot.
uint32_t count_nodes(size_t n, std::unordered_map<size_t, uint32_t>& memo) {
  if (n <= kLeafSize) return 1;
  if (auto it = memo.find(n); it != memo.end()) return it->second;
  const uint32_t c = 1 + count_nodes(n / 2, memo) + count_nodes(n - n / 2, memo);
  memo.emplace(n, c);
  return c;
}

/// True when hit h of primitive id (placed by instance `instance`) beats best: closer, or
/// equally close with a larger (prim_id, instance_id) (the order-independent tie rule of
/// reference.h).
inline bool closer(const Intersection<double>& h, uint32_t id, uint32_t instance, const ReferenceHit& best) {
  return h.hit && (h.t < best.t || (h.t == best.t && (id > best.prim_id ||
                                                      (id == best.prim_id && instance > best.instance_id))));
}

/// The closest hit (Reference::intersect), a policy of the ray walk: of each primitive its
/// first plausible root, taken when closer().
struct ClosestQuery {
  ReferenceHit best;
  /// Nothing beyond the best hit can win; a hit at exactly best.t still may (a tie).
  double limit() const { return best.t; }
  /// Root h of primitive id (placed by `instance`), plausible(t) its plausibility. True when
  /// the primitive's later roots cannot matter.
  template <class Plausible>
  bool offer(const Intersection<double>& h, uint32_t id, uint32_t instance, Plausible&& plausible) {
    if (!closer(h, id, instance, best)) return true;  // its later roots are farther still
    if (!plausible(h.t)) return false;                // a phantom: a later root may be genuine
    best = {h.t, id, h.u, h.v, instance};
    return true;
  }
};

/// Every hit (Reference::all_hits), a policy of the ray walk: every plausible root, in the
/// order of the visits.
struct EveryQuery {
  std::vector<ReferenceHit>& hits;
  static constexpr double limit() { return std::numeric_limits<double>::infinity(); }
  template <class Plausible>
  bool offer(const Intersection<double>& h, uint32_t id, uint32_t instance, Plausible&& plausible) {
    if (plausible(h.t)) hits.push_back({h.t, id, h.u, h.v, instance});
    return false;
  }
};

/// f(i) for every i in [0, n), in parallel over TBB: what every batch call of the reference
/// does, each item independent of the others and of the scheduling.
template <class F>
void each_parallel(size_t n, F&& f) {
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 256), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t i = range.begin(); i < range.end(); ++i) f(i);
  });
}

}  // namespace

/// A bounded primitive (or, in the world's tree, an instance) during the build.
struct Reference::BuildItem {
  Box3f box;
  Vec3d centroid;  ///< box centre, coordinates clamped to the float range (never NaN)
  uint32_t prim_id;

  BuildItem(const Box3f& b, uint32_t id) : box(b), prim_id(id) {
    for (int k = 0; k < 3; ++k)
      centroid[k] = 0.5 * (std::clamp(double(b.lo[k]), -kFloatMax, kFloatMax) +
                           std::clamp(double(b.hi[k]), -kFloatMax, kFloatMax));
  }
};

/// Per-ray constants of the conservative slab test (see Reference::intersect).
struct Reference::RayBoxes {
  double inv[3];        // 1/dir, or +-2^1020 for a +-0 component
  double org_near[3];   // origin moved so that (near face - org_near) is the grown near face
  double org_far[3];    // likewise for the far face
  int near[3], far[3];  // index into Node::bounds of the near and far face per axis
  double tnear;

  RayBoxes(const Rayd& r, double scene_scale) : tnear(r.tnear) {
    // Guard s: every box is grown by s on every side (Ize 2013, "Robust BVH Ray Traversal",
    // JCGT 2(2), grows the exit distance by 2 gamma_3 instead). s = 2^-32 (|org|_inf + M) is
    // 2^21 unit roundoffs of every coordinate and coordinate difference the ray meets, so it
    // dwarfs the three roundings of a slab distance (gamma_3, relative to |face - org|) and
    // the error of a well-conditioned primitive t: a genuine hit's t lies in the computed
    // interval of its primitive's box, a phantom's need not (plausibility). The 2^-880 floor
    // keeps s > 0, so |face - org_near| * 2^1020 > FLT_MAX >= any finite tfar for an origin
    // inside the slab of a +-0 direction component.
    const double s = 0x1p-32 * (max_abs(r.org) + scene_scale) + 0x1p-880;
    for (int k = 0; k < 3; ++k) {
      const double d = r.dir[k];
      inv[k] = d == 0.0 ? std::copysign(0x1p1020, d) : 1.0 / d;
      const bool neg = std::signbit(inv[k]);
      near[k] = neg ? k + 3 : k;
      far[k] = neg ? k : k + 3;
      // Positive direction: near face lo - s, far face hi + s; negative: near hi + s, far lo - s.
      org_near[k] = neg ? r.org[k] - s : r.org[k] + s;
      org_far[k] = neg ? r.org[k] + s : r.org[k] - s;
    }
  }

  /// Computed entry and exit distances of the ray through the box bounds (lo.xyz, hi.xyz)
  /// grown by the guard: no clamping to the ray interval, never NaN (the reciprocals are
  /// finite and non-zero). Monotone: a box containing another gets enter <= and exit >=.
  void interval(const float* bounds, double& enter, double& exit) const {
    const double t0x = (double(bounds[near[0]]) - org_near[0]) * inv[0];
    const double t0y = (double(bounds[near[1]]) - org_near[1]) * inv[1];
    const double t0z = (double(bounds[near[2]]) - org_near[2]) * inv[2];
    const double t1x = (double(bounds[far[0]]) - org_far[0]) * inv[0];
    const double t1y = (double(bounds[far[1]]) - org_far[1]) * inv[1];
    const double t1z = (double(bounds[far[2]]) - org_far[2]) * inv[2];
    enter = std::max(std::max(t0x, t0y), t0z);
    exit = std::min(std::min(t1x, t1y), t1z);
  }

  /// True when the ray may meet the grown box of n within [tnear, tmax]; t_enter is then
  /// the entry distance, the key for near-first order and for culling by the closest hit.
  bool hit(const Node& n, double tmax, double& t_enter) const {
    double enter, exit;
    interval(n.bounds, enter, exit);
    t_enter = std::max(enter, tnear);
    return t_enter <= std::min(exit, tmax);
  }

  /// True when t lies in the computed interval through the grown box b (plausibility).
  bool contains(const Box3f& b, double t) const {
    const float bounds[6] = {b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z};
    double enter, exit;
    interval(bounds, enter, exit);
    return enter <= t && t <= exit;
  }
};

/// A ray query's walk of one tree: the ray at the tree's level (the world's, or an instance's
/// object space) with its slab constants; the query's state is shared by the levels.
template <class Query>
struct Reference::RayWalk {
  const Reference& ref;
  const Ray& ray;  ///< the float world ray (the valid-ray rule of instances)
  const Rayd& r;   ///< the ray in the tree's space
  RayBoxes rb;
  uint32_t instance;  ///< the instance that places the tree, or kNoInstance
  Query& q;

  double limit() const { return std::min(r.tfar, q.limit()); }
  /// A box is entered when its grown slab interval meets [tnear, limit()] (closed); the key is
  /// its entry t.
  bool enter(const Node& n, double& t_enter) const { return rb.hit(n, limit(), t_enter); }
  void leaf(const LeafPrim& p) {
    const uint32_t id = p.prim_id;
    if (id >= ref.instance_base_) {
      // An instance: the ray in its object space, in double, through its mesh's tree; only for
      // a ray whose float object-space image is valid (the backends' rule).
      const uint32_t i = id - ref.instance_base_;
      const InstanceD& in = ref.instances_[i];
      if (!valid_ray(object_ray(ray, in.float_world_to_object))) return;
      const Rayd o = object_ray(r, in.world_to_object);
      const Tree& tree = ref.mesh_trees_[in.mesh];
      RayWalk inner{ref, ray, o, RayBoxes(o, tree.scale), i, q};
      walk(tree, inner);
      return;
    }
    // Plausibility last: the query asks for it only for hits it would keep.
    const auto plausible = [&](double t) { return rb.contains(ref.prim_box(p), t); };
    const auto offer = [&](const Intersection<double>& h) { return q.offer(h, id, instance, plausible); };
    if (id < ref.sphere_base_) {
      const Intersection<double> h = intersect_triangle_watertight(r, Vec3d(p.v[0]), Vec3d(p.v[1]), Vec3d(p.v[2]));
      if (h.hit) offer(h);
      return;
    }
    const auto test = [&](const Rayd& rest) { return ref.intersect_analytic(id, rest); };
    for_each_root(r, test, offer);
  }
};

/// The point query's walk of one tree: the world's, or an instance's mesh tree with its boxes
/// and triangles mapped into the world; the best point and the limits are shared by the levels.
struct Reference::PointWalk {
  const Reference& ref;
  Vec3d p;  ///< the query point, in the world
  double radius;
  double guard;  ///< g of closest_point
  ReferencePoint& best;
  const InstanceD* in = nullptr;  ///< the instance that places the tree, or null
  uint32_t instance = kNoInstance;
  double pad = 0;  ///< with an instance: a bound of its map's rounding of a box

  /// Nothing farther than the best point (or the radius) can count; the guard keeps every
  /// box that may hold a point as close (a tie) despite rounding.
  double limit() const { return std::min(radius, best.distance) + guard; }
  /// A box is entered when its world distance from p is within limit(); the key is that distance.
  bool enter(const Node& n, double& distance) const {
    Vec3d lo(n.bounds[0], n.bounds[1], n.bounds[2]), hi(n.bounds[3], n.bounds[4], n.bounds[5]);
    if (in) {
      // The world box of the mapped box: the centre mapped, the half extents by |L|, grown by pad.
      const Vec3d c = (lo + hi) * 0.5, h = (hi - lo) * 0.5, wc = in->object_to_world.point(c);
      const auto& m = in->object_to_world.m;
      for (int k = 0; k < 3; ++k) {
        const double wh = std::abs(m[k][0]) * h.x + std::abs(m[k][1]) * h.y + std::abs(m[k][2]) * h.z + pad;
        lo[k] = wc[k] - wh;
        hi[k] = wc[k] + wh;
      }
    }
    Vec3d d;
    for (int k = 0; k < 3; ++k) d[k] = std::max(std::max(lo[k] - p[k], p[k] - hi[k]), 0.0);
    distance = length(d);
    return distance <= limit();
  }
  void leaf(const LeafPrim& lp) {
    const uint32_t id = lp.prim_id;
    if (id >= ref.instance_base_) {
      const uint32_t i = id - ref.instance_base_;
      const InstanceD& placed = ref.instances_[i];
      const Tree& tree = ref.mesh_trees_[placed.mesh];
      const auto& m = placed.object_to_world.m;
      // A box's centre and half extents, mapped, are rounded by a few units of 2^-53 of
      // |L| M + |t| (M the mesh tree's largest |coordinate|): 2^-40 of it bounds that.
      const double t = std::max(std::max(std::abs(m[0][3]), std::abs(m[1][3])), std::abs(m[2][3]));
      const double map_pad = 0x1p-40 * (placed.object_to_world.linear_norm() * tree.scale + t);
      PointWalk inner{ref, p, radius, guard, best, &placed, i, map_pad};
      walk(tree, inner);
      return;
    }
    if (id >= ref.sphere_base_) return take(ref.closest_on_analytic(id, p));
    if (zero_area(lp.v[0], lp.v[1], lp.v[2])) return;  // not surface (never hit either)
    Vec3d v[3];
    for (int k = 0; k < 3; ++k) v[k] = in ? in->object_to_world.point(Vec3d(lp.v[k])) : Vec3d(lp.v[k]);
    const SurfacePointT<double> c = closest_on_triangle(p, v[0], v[1], v[2]);
    take({c.p, length(c.p - p), id, instance, c.u, c.v});
  }
  /// Takes candidate c when it is within the radius and closer, or as close with a lower
  /// (prim_id, instance_id) (PointSearch::take's rule): the answer does not depend on the order.
  void take(const ReferencePoint& c) {
    if (c.distance <= radius &&
        std::tie(c.distance, c.prim_id, c.instance_id) < std::tie(best.distance, best.prim_id, best.instance_id))
      best = c;
  }
};

Reference::Reference(const Scene& scene) {
  const auto start = std::chrono::steady_clock::now();
  sphere_base_ = scene.sphere_base();
  quadric_base_ = scene.quadric_base();
  polygon_base_ = scene.polygon_base();
  plane_base_ = scene.plane_base();
  instance_base_ = scene.prim_count();
  RP_CHECK(uint64_t(instance_base_) + scene.instances().size() < kInvalidId, "reference: ", scene.prim_count(),
           " primitives and ", scene.instances().size(), " instances are too many to number");
  for (size_t m = 0; m < scene.meshes().size(); ++m) mesh_base_.push_back(scene.mesh_base(m));
  if (!mesh_base_.empty()) mesh_base_.push_back(scene.triangle_count());

  // Every bounded primitive with its box, in prim_id order: a world mesh's triangles go into
  // the world's tree, an instanced mesh's into its own.
  std::vector<BuildItem> items;
  items.reserve(plane_base_);
  std::vector<std::vector<BuildItem>> mesh_items(scene.meshes().size());
  for (size_t m = 0; m < scene.meshes().size(); ++m) {
    const MeshView& mesh = scene.meshes()[m];
    std::vector<BuildItem>& to = scene.is_instanced(m) ? mesh_items[m] : items;
    for (uint32_t t = 0; t < mesh.triangle_count(); ++t) {
      Box3f b;  // the float box of float vertices: exact
      for (int c = 0; c < 3; ++c) b.extend(mesh.vertex(t, c));
      to.emplace_back(b, scene.mesh_base(m) + t);
    }
  }
  for (uint32_t i = 0; i < scene.spheres().size(); ++i) {
    const Sphere& s = scene.spheres()[i];
    const SphereD sd{Vec3d(s.center), double(s.radius)};
    spheres_.push_back(sd);
    // Padded well beyond the rounding of a grazing double hit, then rounded outward.
    const double pad = 0x1p-10 * sd.radius + 0x1p-20 * max_abs(sd.center);
    const Vec3d r(sd.radius);
    analytic_boxes_.push_back(outward(Box3d(sd.center - r, sd.center + r), pad));
    items.emplace_back(analytic_boxes_.back(), sphere_base_ + i);
  }
  for (uint32_t i = 0; i < scene.quadrics().size(); ++i) {
    const Quadric<float>& q = scene.quadrics()[i].quadric;
    quadrics_.push_back(quadric_cast<double>(q));
    // A hit point, as computed, lies in the clip box: the float clip box bounds it exactly.
    analytic_boxes_.push_back(q.clip);
    items.emplace_back(q.clip, quadric_base_ + i);
  }
  for (uint32_t i = 0; i < scene.polygons().size(); ++i) {
    const PolygonShape& p = scene.polygons()[i];
    PolygonD pd{uint32_t(polygon_vertices_.size()), p.count, {}, p.convex};
    for (uint32_t k = 0; k < p.count; ++k) polygon_vertices_.push_back(Vec3d(scene.polygon_vertices()[p.first + k]));
    const std::span<const Vec3d> verts = std::span<const Vec3d>(polygon_vertices_).subspan(pd.first, pd.count);
    pd.plane = polygon_plane<double>(verts);
    polygons_.push_back(pd);
    // Hits lie on the plane over the projected outline; for a slightly non-planar polygon
    // that region leaves the vertices' box, so the box also holds each vertex lifted along
    // the dropped axis onto the plane (the region is their convex hull's lift).
    Box3d b;
    const int a = pd.plane.drop_axis;
    const ProjectionAxes pa = projection_axes(a);
    for (const Vec3d& v : verts) {
      b.extend(v);
      if (pd.plane.n[a] != 0.0) {
        Vec3d lifted = v;
        lifted[a] = -(pd.plane.d + pd.plane.n[pa.x] * v[pa.x] + pd.plane.n[pa.y] * v[pa.y]) / pd.plane.n[a];
        if (std::isfinite(lifted[a])) b.extend(lifted);
      }
    }
    const double pad = 0x1p-10 * max_component(b.extent()) + 0x1p-20 * std::max(max_abs(b.lo), max_abs(b.hi));
    analytic_boxes_.push_back(outward(b, pad));
    items.emplace_back(analytic_boxes_.back(), polygon_base_ + i);
  }
  for (uint32_t i = 0; i < scene.instances().size(); ++i) {
    const Instance& in = scene.instances()[i];
    const Affine3d m(in.object_to_world);
    const std::optional<Affine3d> w = inverse(m);
    RP_CHECK(w.has_value(), "reference: instance ", i, " is not invertible");  // Scene::add_instance checked it
    // The object-space point of a hit, mapped back, lies within a few double roundings of the
    // world ray, magnified by the transform's condition (at most 2^40, kMaxInstanceScale):
    // a guard of 2^-24 of the box's size and place covers that many times over.
    const double cond = m.linear_norm() * w->linear_norm();
    const double pad = 0x1p-24 * cond * (max_component(Vec3d(in.bounds.extent())) +
                                         std::max(max_abs(Vec3d(in.bounds.lo)), max_abs(Vec3d(in.bounds.hi))));
    const Box3f box = outward(Box3d(Vec3d(in.bounds.lo), Vec3d(in.bounds.hi)), pad);
    instances_.push_back({in.mesh, m, *w, in.world_to_object, box});
    if (!in.bounds.empty()) items.emplace_back(box, instance_base_ + i);
  }
  for (const Plane& p : scene.planes()) planes_.push_back({Vec3d(p.normal), double(p.d)});

  leaf_index_.assign(plane_base_, 0);
  build_tree(items, world_);
  mesh_trees_.resize(scene.meshes().size());
  for (size_t m = 0; m < scene.meshes().size(); ++m)
    if (!mesh_items[m].empty()) build_tree(mesh_items[m], mesh_trees_[m]);
  // Each tree's leaves: a triangle's float corners (read from the scene once), its index.
  for (Tree* t : [&] {
         std::vector<Tree*> all{&world_};
         for (Tree& mt : mesh_trees_) all.push_back(&mt);
         return all;
       }()) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, t->prims.size(), 4096), [&](const tbb::blocked_range<size_t>& range) {
      for (size_t i = range.begin(); i < range.end(); ++i) {
        LeafPrim& p = t->prims[i];
        if (p.prim_id < plane_base_) leaf_index_[p.prim_id] = uint32_t(i);
        if (p.prim_id < sphere_base_) {
          const PrimLocation ref = scene.locate(p.prim_id);
          for (int c = 0; c < 3; ++c) p.v[c] = scene.meshes()[ref.shape].vertex(ref.local, c);
        } else {
          p.v[0] = p.v[1] = p.v[2] = Vec3f(0.0f);
        }
      }
    });
  }
  build_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void Reference::build_tree(std::vector<BuildItem>& items, Tree& tree) {
  if (items.empty()) return;
  std::unordered_map<size_t, uint32_t> memo;
  tree.nodes.resize(count_nodes(items.size(), memo));
  const auto subtree_nodes = [&memo](size_t n) { return n <= kLeafSize ? 1u : memo.at(n); };
  // Median split on the longest axis of the centroid bounds (ties: lower axis; equal
  // centroids: lower prim_id, a total order, so the partition is unique). Depth-first
  // layout: the left child follows its parent, the right child follows the left subtree.
  const auto build = [&](auto&& self, size_t begin, size_t end, uint32_t node) -> void {
    Box3f box;
    Box3d centroids;
    for (size_t i = begin; i < end; ++i) {
      box.extend(items[i].box);
      centroids.extend(items[i].centroid);
    }
    Node& n = tree.nodes[node];
    for (int k = 0; k < 3; ++k) {
      n.bounds[k] = box.lo[k];
      n.bounds[k + 3] = box.hi[k];
    }
    const size_t count = end - begin;
    if (count <= kLeafSize) {
      n.index = uint32_t(begin);
      n.count = uint32_t(count);
      return;
    }
    const Vec3d e = centroids.extent();
    const int axis = e.x >= e.y ? (e.x >= e.z ? 0 : 2) : (e.y >= e.z ? 1 : 2);
    const size_t mid = begin + count / 2;
    std::nth_element(items.begin() + std::ptrdiff_t(begin), items.begin() + std::ptrdiff_t(mid),
                     items.begin() + std::ptrdiff_t(end), [axis](const BuildItem& a, const BuildItem& b) {
                       return a.centroid[axis] < b.centroid[axis] ||
                              (a.centroid[axis] == b.centroid[axis] && a.prim_id < b.prim_id);
                     });
    const uint32_t left = node + 1;
    const uint32_t right = left + subtree_nodes(mid - begin);
    n.index = right;
    n.count = 0;
    if (count > kParallelBuild) {
      tbb::parallel_invoke([&] { self(self, begin, mid, left); }, [&] { self(self, mid, end, right); });
    } else {
      self(self, begin, mid, left);
      self(self, mid, end, right);
    }
  };
  build(build, 0, items.size(), 0);
  tree.prims.resize(items.size());
  for (size_t i = 0; i < items.size(); ++i) tree.prims[i].prim_id = items[i].prim_id;
  double m = 0;
  for (float b : tree.nodes[0].bounds) m = std::max(m, std::abs(double(b)));
  tree.scale = std::min(m, kFloatMax);
}

Box3f Reference::prim_box(const LeafPrim& p) const noexcept {
  if (p.prim_id >= instance_base_) return instances_[p.prim_id - instance_base_].box;
  if (p.prim_id >= sphere_base_) return analytic_boxes_[p.prim_id - sphere_base_];
  Box3f b;  // the same exact float box the build used
  for (const Vec3f& v : p.v) b.extend(v);
  return b;
}

Intersection<double> Reference::intersect_analytic(uint32_t id, const Rayd& r) const noexcept {
  if (id < quadric_base_) {
    const SphereD& s = spheres_[id - sphere_base_];
    return intersect_sphere_algebraic(r, s.center, s.radius);
  }
  if (id < polygon_base_) return intersect_quadric(r, quadrics_[id - quadric_base_]);
  const PolygonD& pd = polygons_[id - polygon_base_];
  return intersect_polygon<double>(r, std::span<const Vec3d>(polygon_vertices_).subspan(pd.first, pd.count), pd.plane,
                                   pd.convex);
}

template <class Walk>
void Reference::walk(const Tree& tree, Walk& w) {
  // Near-first depth-first: of two children to enter, the one of the smaller key first (the
  // left one at equal keys), the other deferred with its key and skipped when popped beyond
  // the walk's limit then (closed: a tie at exactly the limit is still visited).
  if (tree.nodes.empty()) return;
  struct Entry {
    uint32_t node;
    double key;
  };
  Entry stack[kStackSize];
  int sp = 0;
  double key_root;
  if (!w.enter(tree.nodes[0], key_root)) return;
  uint32_t ni = 0;
  for (;;) {
    const Node& n = tree.nodes[ni];
    if (n.count == 0) {
      double kl, kr;
      const bool hl = w.enter(tree.nodes[ni + 1], kl);
      const bool hr = w.enter(tree.nodes[n.index], kr);
      if (hl && hr) {
        RP_DCHECK(sp < kStackSize);
        if (kr < kl) {
          stack[sp++] = {ni + 1, kl};
          ni = n.index;
        } else {
          stack[sp++] = {n.index, kr};
          ni = ni + 1;
        }
        continue;
      }
      if (hl || hr) {
        ni = hl ? ni + 1 : n.index;
        continue;
      }
    } else {
      for (uint32_t k = n.index; k < n.index + n.count; ++k) w.leaf(tree.prims[k]);
    }
    for (;;) {
      if (sp == 0) return;
      const Entry e = stack[--sp];
      if (e.key <= w.limit()) {
        ni = e.node;
        break;
      }
    }
  }
}

template <class Query>
void Reference::trace(const Ray& ray, Query& q) const {
  if (!valid_ray(ray)) return;
  const Rayd r{Vec3d(ray.org), double(ray.tnear), Vec3d(ray.dir), double(ray.tfar)};
  RayWalk<Query> w{*this, ray, r, RayBoxes(r, world_.scale), kNoInstance, q};
  walk(world_, w);
  for (uint32_t k = 0; k < planes_.size(); ++k) {  // unbounded: every hit plausible
    const Intersection<double> h = intersect_plane(r, planes_[k].normal, planes_[k].d);
    if (h.hit) q.offer(h, plane_base_ + k, kNoInstance, [](double) { return true; });
  }
}

ReferenceHit Reference::intersect(const Ray& ray) const noexcept {
  ClosestQuery q;
  trace(ray, q);
  return q.best;
}

std::vector<ReferenceHit> Reference::all_hits(const Ray& ray) const {
  std::vector<ReferenceHit> hits;
  EveryQuery q{hits};
  trace(ray, q);
  std::sort(hits.begin(), hits.end(), [](const ReferenceHit& a, const ReferenceHit& b) {
    return std::tie(a.t, a.prim_id, a.instance_id) < std::tie(b.t, b.prim_id, b.instance_id);
  });
  return hits;
}

ReferenceHitList Reference::all_hits(std::span<const Ray> rays, size_t max_per_ray) const {
  std::vector<std::vector<ReferenceHit>> each(rays.size());
  each_parallel(rays.size(), [&](size_t i) {
    each[i] = all_hits(rays[i]);
    if (max_per_ray && each[i].size() > max_per_ray) each[i].resize(max_per_ray);
  });
  ReferenceHitList list;
  list.offsets.reserve(rays.size() + 1);
  list.offsets.push_back(0);
  for (const std::vector<ReferenceHit>& h : each) list.offsets.push_back(list.offsets.back() + h.size());
  list.hits.reserve(list.offsets.back());
  for (const std::vector<ReferenceHit>& h : each) list.hits.insert(list.hits.end(), h.begin(), h.end());
  return list;
}

void Reference::count_hits(std::span<const Ray> rays, std::span<uint32_t> counts) const {
  RP_CHECK(rays.size() == counts.size(), "Reference::count_hits: ", rays.size(), " rays but ", counts.size(),
           " counts");
  each_parallel(rays.size(), [&](size_t i) { counts[i] = uint32_t(all_hits(rays[i]).size()); });
}

ReferencePoint Reference::closest_on_analytic(uint32_t id, const Vec3d& p) const noexcept {
  ReferencePoint out;
  out.prim_id = id;
  if (id < quadric_base_) {
    const SphereD& s = spheres_[id - sphere_base_];
    const Vec3d d = p - s.center;
    const double len = length(d);
    // The centre itself: every point of the sphere is as close; the one on +x.
    out.point = len > 0.0 ? s.center + d * (s.radius / len) : s.center + Vec3d(s.radius, 0.0, 0.0);
    const Vec2<double> uv = sphere_uv(s.center, s.radius, out.point);
    out.u = uv.x;
    out.v = uv.y;
  } else if (id >= plane_base_) {
    const PlaneD& pl = planes_[id - plane_base_];
    out.point = closest_on_plane(p, pl.normal, pl.d);
  } else {
    RP_DCHECK(id >= polygon_base_);  // quadrics are refused before any walk
    const PolygonD& pd = polygons_[id - polygon_base_];
    out.point =
        closest_on_polygon<double>(p, std::span<const Vec3d>(polygon_vertices_).subspan(pd.first, pd.count), pd.plane);
  }
  out.distance = length(out.point - p);
  return out;
}

void Reference::check_no_quadrics() const {
  RP_CHECK(quadrics_.empty(), "reference: closest points: the scene has ", quadrics_.size(), " quadric",
           quadrics_.size() == 1 ? "" : "s", " (quadrics have no closest-point routine)");
}

ReferencePoint Reference::closest_point(const PointQuery& q) const {
  check_no_quadrics();
  ReferencePoint best;
  if (!valid_point_query(q)) return best;
  const Vec3d p(q.point);
  PointWalk w{*this, p, double(q.radius), 0x1p-32 * (max_abs(p) + world_.scale), best};
  walk(world_, w);
  for (uint32_t k = 0; k < planes_.size(); ++k) w.take(closest_on_analytic(plane_base_ + k, p));
  return best;
}

void Reference::closest_points(std::span<const PointQuery> queries, std::span<ReferencePoint> out) const {
  RP_CHECK(queries.size() == out.size(), "Reference::closest_points: ", queries.size(), " queries but ", out.size(),
           " answers");
  check_no_quadrics();
  each_parallel(queries.size(), [&](size_t i) { out[i] = closest_point(queries[i]); });
}

bool Reference::plausible(const Ray& ray, uint32_t prim_id, double t, uint32_t instance) const noexcept {
  if (!valid_ray(ray) || prim_id >= plane_base_ + planes_.size()) return false;
  if (prim_id >= plane_base_) return instance == kNoInstance;
  const Rayd r{Vec3d(ray.org), double(ray.tnear), Vec3d(ray.dir), double(ray.tfar)};
  // The primitive's tree: the world's, or the instance's mesh's (which must hold it).
  const bool triangle = prim_id < sphere_base_;
  const size_t mesh = triangle ? size_t(std::upper_bound(mesh_base_.begin(), mesh_base_.end() - 1, prim_id) -
                                        mesh_base_.begin() - 1)
                               : 0;
  const bool instanced = triangle && !mesh_trees_[mesh].prims.empty();
  if (instance == kNoInstance) {
    if (instanced) return false;
    return RayBoxes(r, world_.scale).contains(prim_box(world_.prims[leaf_index_[prim_id]]), t);
  }
  if (instance >= instances_.size() || !instanced || instances_[instance].mesh != mesh) return false;
  const InstanceD& in = instances_[instance];
  if (!valid_ray(object_ray(ray, in.float_world_to_object))) return false;
  const Rayd o = object_ray(r, in.world_to_object);
  const Tree& tree = mesh_trees_[mesh];
  return RayBoxes(o, tree.scale).contains(prim_box(tree.prims[leaf_index_[prim_id]]), t);
}

void Reference::intersect(std::span<const Ray> rays, std::span<ReferenceHit> hits) const {
  RP_CHECK(rays.size() == hits.size(), "Reference::intersect: ", rays.size(), " rays but ", hits.size(), " hits");
  each_parallel(rays.size(), [&](size_t i) { hits[i] = intersect(rays[i]); });
}

size_t Reference::bytes() const {
  size_t trees = world_.nodes.size() * sizeof(Node) + world_.prims.size() * sizeof(LeafPrim);
  for (const Tree& t : mesh_trees_) trees += t.nodes.size() * sizeof(Node) + t.prims.size() * sizeof(LeafPrim);
  return trees + leaf_index_.size() * sizeof(uint32_t) + mesh_base_.size() * sizeof(uint32_t) +
         instances_.size() * sizeof(InstanceD) + mesh_trees_.size() * sizeof(Tree) +
         analytic_boxes_.size() * sizeof(Box3f) + spheres_.size() * sizeof(SphereD) +
         quadrics_.size() * sizeof(Quadric<double>) + polygons_.size() * sizeof(PolygonD) +
         polygon_vertices_.size() * sizeof(Vec3d) + planes_.size() * sizeof(PlaneD);
}

}  // namespace rp
