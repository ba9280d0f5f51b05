#pragma once
/// The double-precision reference intersector: the arbiter `raypack diff` consults when two
/// backends disagree. It gives the answer of a brute-force loop over every primitive in double
/// (tests/backends/oracle.h), fast enough for millions of rays.
///
/// What it computes. The ray is converted exactly to double; each primitive is tested by the
/// double instantiation of its core/geometry/ routine on its float data converted exactly to
/// double, against the ray's whole closed interval [tnear, tfar]:
/// - triangles: intersect_triangle_watertight<double> (Woop, Benthin & Wald 2013);
/// - spheres: intersect_sphere_algebraic<double>;
/// - quadrics: intersect_quadric<double> on the converted coefficients, center and clip;
/// - polygons: intersect_polygon<double> with polygon_plane<double> of the converted vertices;
/// - planes: intersect_plane<double>.
/// A hit of a bounded primitive counts only when it is plausible (Reference::plausible): its
/// t lies in the ray's interval through the primitive's box grown by a tiny guard. This
/// drops phantom hits, which are rounding artefacts: e.g. for a ray lying exactly in a
/// triangle's plane the watertight test's determinant is rounding noise, and it may report
/// a "hit" far outside the triangle (seen on rays between points of a 0.25 grid). The guard
/// is 2^21 unit roundoffs, so every well-conditioned hit is plausible and the answer differs
/// from the brute-force loop of tests/backends/oracle.h only where that loop returns a
/// phantom (or, at exactly equal t, picks the other primitive of a tie).
/// The answer is the plausible hit of smallest t (a sphere or quadric is asked for its roots
/// in order, for_each_root, until one is plausible); among hits at exactly the same t the
/// LARGEST (prim_id, instance_id) wins. Because every primitive is tested against the full
/// interval (not one shortened by earlier hits), this rule does not depend on the order
/// primitives are visited in: the result is a function of the scene and the ray alone,
/// whatever the BVH or the thread count. It is also what an ascending-id scan that replaces
/// at `t <= best` gives (oracle.h; Scene::intersect_planes, where a plane takes a tie).
///
/// Instances (Scene::instances): the ray is taken into the instance's object space in double
/// by the double inverse of the instance's float object_to_world (not by its float
/// world_to_object, which the backends use), and tested against the instanced mesh there,
/// plausibility included, in the mesh's own tree; the instance is traced only for rays whose
/// float object-space image (rp::object_ray with Instance::world_to_object) obeys the
/// valid-ray rule, the rule every backend follows.
///
/// Every hit (Reference::all_hits, count_hits): the same tests, the same plausibility, the
/// same instances and planes, every root. A primitive's hits are found as the backends find
/// them (for_each_root, core/geometry/intersection.h: each next root searched from the next
/// representable t after the last), so a sphere or quadric crossed twice counts twice, a
/// double root (a tangent) once, a triangle, polygon or plane once; each root counts when it
/// is plausible. The list of a ray is sorted by (t, prim_id, instance_id); each primitive is
/// in one leaf, so no hit is listed twice. intersect(ray) is the last of the ray's hits at
/// the smallest t (its tie rule takes the largest id).
///
/// Closest point (Reference::closest_point): rp::ClosestPoint's conventions (core/queries.h),
/// computed in double by the double instantiations of core/geometry/closest_point.h on each
/// primitive's float data converted exactly to double:
/// - triangles: closest_on_triangle<double> (Ericson's Voronoi regions), Embree's
///   barycentrics as (u, v); zero-area triangles (zero_area in float) are not surface;
/// - instanced triangles: the corners mapped into the world by the double of the instance's
///   float object_to_world (Affine3d::point of each converted corner), then as a world
///   triangle, so the distance is the world one with no float rounding on the way ((u, v)
///   hold in the mesh's space too: an affine map keeps barycentrics);
/// - spheres: as Scene::closest_on_analytic, in double: the point where the ray from the
///   centre through the query point leaves the sphere (from the centre itself, the point on
///   +x), its sphere_uv as (u, v);
/// - polygons: closest_on_polygon<double> with the polygon's double plane; planes:
///   closest_on_plane<double>; (u, v) = 0 for both.
/// The distance is |point - query point| in double. The answer is the candidate of smallest
/// distance among those with distance <= radius; at exactly equal distance the LOWEST
/// (prim_id, instance_id) wins (the backends' rule, unlike intersect's). An invalid query
/// (valid_point_query false) finds nothing. A scene with quadrics is refused with rp::Error,
/// as the backends refuse it: a clipped quadric has no closed-form closest point.
///
/// How. A binary BVH over the bounded primitives (median split on the longest axis of the
/// centroid bounds, depth-first layout, leaves of up to 4 primitives), with float boxes that
/// bound the float geometry exactly (triangles, quadric clip boxes) or outward-rounded and
/// padded (spheres, polygons, instances), traversed near-first in double with a conservative
/// slab test (see Reference::intersect). An instance is an entry of that tree whose box is
/// its mesh's box mapped into the world; each instanced mesh has a tree of its own, in its
/// object space, built once. Unbounded planes are tested beside it. One loop walks every
/// tree for every query (Reference::walk, madmann91/bvh's traversal with the query as a
/// template policy): a ray query's key for a box is its entry t, the point query's its
/// distance from the query point; each query says how far it still looks and what a leaf's
/// primitive (an instance: its mesh's tree, walked with the same policy) does to it.

#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "base/bbox.h"
#include "base/math.h"
#include "core/affine.h"
#include "core/geometry/intersection.h"
#include "core/geometry/polygon.h"
#include "core/geometry/quadric.h"
#include "core/queries.h"
#include "core/ray.h"

namespace rp {

class Scene;

/// Closest hit in double precision; t is in units of the ray direction's length.
/// On a miss: prim_id == kInvalidId, t == +inf, u == v == 0. (u, v) as rp::Hit documents:
/// Embree's barycentrics for triangles, the primitive's surface parameters otherwise.
struct ReferenceHit {
  double t = std::numeric_limits<double>::infinity();
  uint32_t prim_id = kInvalidId;
  double u = 0, v = 0;
  uint32_t instance_id = kNoInstance;  ///< as rp::Hit

  constexpr bool hit() const { return prim_id != kInvalidId; }
};

/// `h` as a float Hit (t, u, v rounded to float; a miss stays Hit{}).
inline Hit to_hit(const ReferenceHit& h) {
  return h.hit() ? Hit{float(h.t), h.prim_id, float(h.u), float(h.v), h.instance_id} : Hit{};
}

/// Every hit of some rays in double (Reference::all_hits): ray i's are of(i), sorted by (t,
/// prim_id, instance_id).
using ReferenceHitList = HitListOf<ReferenceHit>;

/// The closest point of the surface to a query point in double (Reference::closest_point),
/// with rp::ClosestPoint's fields and meaning. Not found (no surface within the radius, an
/// invalid query): prim_id == kInvalidId, distance == +inf, point == 0, u == v == 0.
struct ReferencePoint {
  Vec3d point{0.0};
  double distance = std::numeric_limits<double>::infinity();  ///< |point - query point|
  uint32_t prim_id = kInvalidId;
  uint32_t instance_id = kNoInstance;  ///< the instance that places the triangle, as Hit's
  double u = 0, v = 0;                 ///< as ClosestPoint's: barycentrics, a sphere's parameters, else 0

  constexpr bool found() const { return prim_id != kInvalidId; }
};

/// Built once from a Scene (whose data it copies: the scene may go away afterwards), then
/// immutable and safe to query from many threads at once.
class Reference {
 public:
  /// Builds the BVH over every triangle, sphere, quadric and polygon of `scene` (planes are
  /// kept beside it), in parallel over TBB; the structure is the same for any thread count.
  explicit Reference(const Scene& scene);

  /// Closest plausible hit of `ray` (converted exactly to double) within [tnear, tfar], both
  /// ends closed; invalid rays (valid_ray() false) miss. See the file comment for the rules.
  ///
  /// Traversal never changes the answer (Ize 2013, "Robust BVH Ray Traversal", JCGT 2(2),
  /// made exact): slab distances are computed in double against every box grown by a
  /// per-ray guard s = 2^-32 (|org|_inf + M), M the scene's largest |coordinate|, and a
  /// primitive's hit is plausible exactly when its t lies in the interval computed the same
  /// way for the primitive's own box. Node boxes contain their primitives' boxes and the
  /// computed distances are monotone in the face coordinates, so every node on the way to a
  /// plausible hit is entered: faces, edges and vertices of boxes, origins on faces,
  /// zero-thickness boxes and hits at exactly tnear, tfar or the closest t so far (ties) are
  /// never culled. The guard, 2^21 unit roundoffs of the ray's coordinates, exceeds Ize's
  /// 2 gamma_3 widening and the rounding of every well-conditioned primitive t, so only
  /// phantoms fail plausibility. A +-0 direction component gets the finite reciprocal
  /// +-2^1020 instead of +-inf, so no product is 0 * inf: slab distances are never NaN and
  /// plain min/max suffice.
  ReferenceHit intersect(const Ray& ray) const noexcept;

  /// hits[i] = intersect(rays[i]) for every i, in parallel over TBB (each ray independent,
  /// so the result does not depend on scheduling). Throws rp::Error when the sizes differ.
  void intersect(std::span<const Ray> rays, std::span<ReferenceHit> hits) const;

  /// Every plausible hit of `ray` (converted exactly to double) within [tnear, tfar], both
  /// ends closed, sorted by (t, prim_id, instance_id): each root of each primitive, on the
  /// rules of the file comment. Empty for an invalid ray (valid_ray() false).
  std::vector<ReferenceHit> all_hits(const Ray& ray) const;
  /// all_hits of every ray, in parallel over TBB (ray i's hits are the list's of(i)); with
  /// max_per_ray > 0, the first max_per_ray of each, as Backend::all_hits.
  ReferenceHitList all_hits(std::span<const Ray> rays, size_t max_per_ray = 0) const;
  /// counts[i] = all_hits(rays[i]).size() for every i, in parallel over TBB. Throws rp::Error
  /// when the sizes differ.
  void count_hits(std::span<const Ray> rays, std::span<uint32_t> counts) const;

  /// The closest point of the surface to q.point within q.radius, on the rules of the file
  /// comment: triangles (world and instanced), spheres, polygons, planes. Not found for an
  /// invalid query. Throws rp::Error for a scene with quadrics.
  ///
  /// The walk never changes the answer: a box is entered when its distance from the query
  /// point, computed in double, is at most the best distance so far (or the radius) plus a
  /// guard g = 2^-32 (|p|_inf + M), M the scene's largest |coordinate|. Every candidate's
  /// computed point lies in its primitive's box up to a few double roundings of coordinates
  /// below M + |p|_inf, and so does a computed distance: g dwarfs them, so a candidate in a
  /// skipped box is farther than the best, never as close (ties are never culled). An instance's mesh tree is walked
  /// with its boxes mapped into the world (the centre by the map, the half extents by |L|),
  /// each grown by a bound of the map's rounding.
  ReferencePoint closest_point(const PointQuery& q) const;
  /// out[i] = closest_point(queries[i]) for every i, in parallel over TBB. Throws rp::Error
  /// when the sizes differ or the scene has quadrics.
  void closest_points(std::span<const PointQuery> queries, std::span<ReferencePoint> out) const;

  /// True when a hit of primitive prim_id (placed by instance `instance`, or by none) at t is
  /// plausible for ray: prim_id is a plane, or t lies in the ray's guarded slab interval
  /// through the primitive's box (see intersect), in the instance's object space for an
  /// instanced triangle. False for an invalid ray, a prim_id or instance out of range, or a
  /// primitive the instance does not place. For diagnostics and for tests that mirror the
  /// reference by brute force.
  bool plausible(const Ray& ray, uint32_t prim_id, double t, uint32_t instance = kNoInstance) const noexcept;

  /// Wall-clock seconds the constructor took.
  double build_seconds() const { return build_seconds_; }
  /// Bytes of the acceleration structure and the converted primitive data (capacity excluded).
  size_t bytes() const;
  /// BVH nodes of the world's tree (0 when the scene has no bounded primitive).
  size_t node_count() const { return world_.nodes.size(); }

 private:
  /// Binary BVH node in depth-first order; the left child of an interior node follows it.
  /// 32 bytes.
  struct Node {
    float bounds[6];  ///< lo.x, lo.y, lo.z, hi.x, hi.y, hi.z (closed box)
    uint32_t index;   ///< interior: right child; leaf: first entry of prims_
    uint32_t count;   ///< 0 for an interior node, else primitives in the leaf (1..4)
  };
  /// One primitive of a leaf: the float vertices of a triangle (unused for other kinds, whose
  /// converted data are looked up by prim_id). 40 bytes.
  struct LeafPrim {
    Vec3f v[3];
    uint32_t prim_id;
  };
  struct SphereD {
    Vec3d center;
    double radius;
  };
  struct PolygonD {
    uint32_t first, count;  ///< range of polygon_vertices_
    PolygonPlane<double> plane;
    bool convex;
  };
  struct PlaneD {
    Vec3d normal;
    double d;
  };
  /// A tree over some bounded primitives: the world's, or an instanced mesh's in its object
  /// space. An entry of the world's tree with prim_id >= instance_base_ is instance
  /// prim_id - instance_base_.
  struct Tree {
    std::vector<Node> nodes;
    std::vector<LeafPrim> prims;
    double scale = 0;  ///< M: largest |coordinate| of the root box, capped to FLT_MAX
  };
  struct InstanceD {
    uint32_t mesh;
    Affine3d object_to_world;  ///< the instance's float object_to_world, in double (exact)
    Affine3d world_to_object;  ///< the double inverse of the instance's float object_to_world
    Affine3f float_world_to_object;  ///< Instance::world_to_object, for the valid-ray rule
    Box3f box;                       ///< the world box of the instance's tree entry
  };
  struct RayBoxes;
  struct BuildItem;
  template <class Query>
  struct RayWalk;
  struct PointWalk;

  void build_tree(std::vector<BuildItem>& items, Tree& tree);
  /// The one traversal loop: near-first and depth-first over `tree`, for any walk w (a ray
  /// query's RayWalk, the point query's PointWalk). w.enter(node, key) says whether a node may
  /// hold something of interest and gives its key (entry t, distance), w.limit() the key
  /// beyond which a deferred node is skipped, w.leaf(prim) visits a leaf's primitive.
  template <class Walk>
  static void walk(const Tree& tree, Walk& w);
  /// Runs ray query q (a policy: ClosestQuery, EveryQuery in reference.cpp) over the world's
  /// tree, the instances and the planes; nothing for an invalid ray.
  template <class Query>
  void trace(const Ray& ray, Query& q) const;
  /// The closest hit of sphere, quadric or polygon `id` along r (its core/geometry routine).
  Intersection<double> intersect_analytic(uint32_t id, const Rayd& r) const noexcept;
  /// The point of sphere, polygon or plane `id` closest to p, with its distance.
  ReferencePoint closest_on_analytic(uint32_t id, const Vec3d& p) const noexcept;
  /// Throws rp::Error when the scene has quadrics (closest points refuse them).
  void check_no_quadrics() const;
  /// The BVH box of bounded primitive p (its t-interval decides plausibility).
  Box3f prim_box(const LeafPrim& p) const noexcept;

  Tree world_;
  std::vector<Tree> mesh_trees_;       ///< per mesh; empty but for instanced meshes
  std::vector<InstanceD> instances_;
  uint32_t instance_base_ = 0;         ///< the world tree's entry ids from here on are instances
  std::vector<uint32_t> leaf_index_;   ///< prim_id -> index in its tree's prims (bounded primitives)
  std::vector<uint32_t> mesh_base_;    ///< first prim_id of each mesh, then the triangle count
  std::vector<Box3f> analytic_boxes_;  ///< boxes of spheres, quadrics, polygons (id - sphere_base_)
  std::vector<SphereD> spheres_;
  std::vector<Quadric<double>> quadrics_;
  std::vector<PolygonD> polygons_;
  std::vector<Vec3d> polygon_vertices_;
  std::vector<PlaneD> planes_;
  uint32_t sphere_base_ = 0, quadric_base_ = 0, polygon_base_ = 0, plane_base_ = 0;
  double build_seconds_ = 0;
};

}  // namespace rp
