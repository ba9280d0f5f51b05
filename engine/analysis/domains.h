#pragma once
/// A simulation of data-parallel ray tracing, for scenes larger than one node's memory: the
/// scene's triangles split into spatial domains, each owned by one rank, and each ray sent from
/// owner to owner as such a renderer would send it (the domain-parallel schedule of Navrátil,
/// Childs, Fussell and Lin, "Exploring the Spectrum of Dynamic Scheduling Algorithms for
/// Scalable Distributed-Memory Ray Tracing", IEEE TVCG 20(6), 2014; OSPRay's data-distributed
/// mode). It counts what crosses the network, not time: how many owners each ray visits.

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "engine/backend.h"
#include "engine/bbox.h"
#include "engine/scene.h"

namespace rp {

/// A scene's triangles in `parts.size()` domains: each a scene of its own (one mesh, three
/// vertices per triangle), with the bounds of its triangles (which may overlap other
/// domains' bounds).
struct Domains {
  std::vector<Scene> parts;
  std::vector<Box3f> bounds;
};

/// Splits the triangles of `scene` into `count` domains of equal triangle counts (within one):
/// recursive splits at the median of the triangles' centroids along the longest axis of their
/// bounds (a k-d partition; `count` need not be a power of two). Throws rp::Error when the
/// scene holds anything but triangle meshes or fewer triangles than `count`.
Domains split_domains(const Scene& scene, int count);

/// What following a batch of rays through the domains cost.
struct Traffic {
  uint64_t rays = 0;          ///< rays followed (those entering no domain's bounds included)
  uint64_t visits = 0;        ///< domains that traced a ray, summed over the rays
  uint64_t forwards = 0;      ///< rays sent from one owner to the next: visits after each ray's first
  uint64_t one_domain = 0;    ///< rays traced by exactly one domain
  uint64_t no_domain = 0;     ///< rays that enter no domain's bounds
  uint64_t max_visits = 0;    ///< the most domains one ray visited
  uint64_t hits = 0;          ///< rays that hit (closest) or are occluded (any hit)
  uint64_t disagreements = 0; ///< rays whose answer differs from one backend over the whole scene (should be 0)
};

/// Follows `rays` through `domains` (with `backends[d]` built over domains.parts[d]): each ray
/// goes to the domains whose bounds it enters within [tnear, tfar], nearest entry first; each
/// traces it against its own triangles with the ray's tfar shortened to the closest hit found so
/// far, and the ray stops once that hit is nearer than the next domain's entry (closest hit) or
/// at the first domain that blocks it (`any_hit`, shadow rays). `whole` is a backend over the
/// whole scene, whose answers the domains' must reproduce (Traffic::disagreements).
Traffic follow_rays(const Domains& domains, std::span<const std::unique_ptr<Backend>> backends, const Backend& whole,
                    std::span<const Ray> rays, bool any_hit);

}  // namespace rp
