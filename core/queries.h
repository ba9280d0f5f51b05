#pragma once
/// The queries beyond the closest and any hit (core/backend.h), their inputs and answers:
/// - masks and hit filters for intersect and occluded (TraceOptions), as Embree's ray masks,
///   geometry masks and filter functions;
/// - every hit along a ray (Backend::all_hits) and their number (Backend::count_hits);
/// - the closest point of the surface to a point (Backend::closest_points), and from it the
///   distance, inside/outside and the signed distance (rp::inside, rp::signed_distance).
/// Every backend answers each with the same conventions as its hits: the valid-ray rule, the
/// closed interval [tnear, tfar], ties by the lowest (prim_id, instance_id), the same answer
/// whatever the thread count.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <span>
#include <vector>

#include "base/math.h"
#include "core/ray.h"

namespace rp {

class Backend;

/// A hit the traversal found, offered to a filter before it counts.
struct HitCandidate {
  const Ray& ray;
  size_t ray_index;      ///< the ray's index in the call's span
  Hit hit;               ///< t, prim_id, u, v, instance_id of the candidate
  uint32_t geometry_id;  ///< Scene::geometry_of(hit.prim_id)
};

/// Any-hit filter (Embree's intersection and occlusion filter functions): false rejects the
/// candidate, and the ray goes on as if the primitive were not there at that t (alpha
/// cut-outs, transparent shadows, rejecting a ray's own surface). It may be called for a
/// candidate farther than the closest hit found later, more than once for a candidate and in
/// any order, from several threads at once: it must be a pure function of its candidate.
using HitFilter = std::function<bool(const HitCandidate&)>;

/// Per-call settings of a ray query.
struct TraceOptions {
  /// Ray masks: ray i sees geometry g only when (masks[i] & Scene::mask(g)) != 0 (Embree's
  /// rule). Empty: every ray's mask is 0xffffffff; one element: the mask of every ray; else one
  /// per ray.
  std::span<const uint32_t> masks;
  /// Hits the filter rejects do not count (empty: every hit counts).
  HitFilter filter;

  /// The mask of ray i.
  uint32_t mask(size_t i) const { return masks.empty() ? ~0u : masks[masks.size() == 1 ? 0 : i]; }
  /// True when neither masks nor a filter can reject anything.
  bool passes_all() const { return !filter && (masks.empty() || (masks.size() == 1 && masks[0] == ~0u)); }
};

/// Every hit along some rays: the hits of ray i are hits[offsets[i] .. offsets[i + 1]),
/// sorted by (t, prim_id, instance_id). H is rp::Hit (Backend::all_hits) or the double
/// reference's hit (rp::ReferenceHit, analysis/reference.h).
template <class H>
struct HitListOf {
  std::vector<size_t> offsets;  ///< rays + 1 entries
  std::vector<H> hits;
  size_t count(size_t ray) const { return offsets[ray + 1] - offsets[ray]; }
  std::span<const H> of(size_t ray) const { return {hits.data() + offsets[ray], count(ray)}; }
};
/// Every hit along some rays, in float (Backend::all_hits).
using HitList = HitListOf<Hit>;

/// A closest-point query: the point and the largest distance of interest.
struct PointQuery {
  Vec3f point;
  float radius = std::numeric_limits<float>::infinity();  ///< >= 0; nothing farther is found
};

/// The closest point of the surface to a query point. Not found (prim_id == kInvalidId,
/// distance +inf): no surface within the radius, or an invalid query (a point outside the
/// coordinate range, a NaN or negative radius).
struct ClosestPoint {
  Vec3f point{0.0f};
  float distance = std::numeric_limits<float>::infinity();  ///< |point - query point|
  uint32_t prim_id = kInvalidId;
  uint32_t instance_id = kNoInstance;  ///< the instance that places the triangle, as Hit's
  /// (u, v) of the point: Embree's barycentrics for a triangle (point = (1-u-v) v0 + u v1 +
  /// v v2, in the mesh's own space for an instance), the sphere's surface parameters, 0 for
  /// polygons and planes.
  float u = 0.0f, v = 0.0f;
  bool found() const { return prim_id != kInvalidId; }
};

/// True when every closest-point query of `q` can be answered: its point within the
/// coordinate range, its radius >= 0 (not NaN).
inline bool valid_point_query(const PointQuery& q) { return in_coordinate_range(q.point) && q.radius >= 0.0f; }

/// The closest point found so far for one query.
struct PointSearch {
  Vec3f point;  ///< the query point, in the world
  float radius;
  ClosestPoint best;
  /// Squared world distance beyond which a box holds nothing closer: the best distance (or
  /// the radius) widened past the rounding of box distances.
  float limit2;

  explicit PointSearch(const PointQuery& q) : point(q.point), radius(q.radius), limit2(widened(q.radius)) {}

  static float widened(float d) { return d * d * 1.00001f; }

  /// Takes candidate `c` when it is within the radius and closer, or as close with a lower
  /// (prim_id, instance_id): the answer does not depend on the order of the visits.
  void take(const ClosestPoint& c) {
    if (!(c.distance <= radius)) return;
    if (c.distance < best.distance ||
        (c.distance == best.distance &&
         (c.prim_id < best.prim_id || (c.prim_id == best.prim_id && c.instance_id < best.instance_id)))) {
      best = c;
      limit2 = widened(c.distance);
    }
  }
};

/// The three directions of the inside test: far from the coordinate axes and from each other,
/// so that no two of them meet one edge of an axis-aligned model at once.
inline constexpr Vec3f kInsideDirections[3] = {
    {0.5773502f, 0.6164414f, 0.5354682f}, {-0.7071068f, 0.3090170f, 0.6360920f}, {0.2672612f, -0.8017837f, 0.5345225f}};

/// Whether each point is inside the scene's closed surfaces: by the parity of the number of
/// surfaces crossed along three rays from the point (kInsideDirections, count_hits over
/// [0, +inf)), and the majority of the three. For a closed (watertight) mesh, a sphere or a
/// closed union of them this is the point's inside, except where a ray grazes an edge or a
/// vertex, which the majority outvotes. An open mesh has no inside: a point counts as inside
/// when two of the three rays cross it an odd number of times. Planes are crossed by every ray
/// that meets them and quadrics' inside depends on their clip box: leave them out of scenes
/// whose inside matters. Points outside the coordinate range are outside. Parallel over TBB.
void inside(const Backend& backend, std::span<const Vec3f> points, std::span<uint8_t> out);

/// Signed distance of each point to the surface: the closest-point distance, negative inside
/// (rp::inside). +inf with no surface (NaN for a point outside the coordinate range).
void signed_distance(const Backend& backend, std::span<const Vec3f> points, std::span<float> out);

}  // namespace rp
