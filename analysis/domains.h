#pragma once
/// A simulation of data-parallel ray tracing, for scenes larger than one node's memory: space
/// split into disjoint cells (domains), each owned by one rank that holds the triangles reaching
/// into it, and each ray sent from owner to owner as such a renderer would send it (the
/// domain-parallel schedule of Navrátil, Childs, Fussell and Lin, "Exploring the Spectrum of
/// Dynamic Scheduling Algorithms for Scalable Distributed-Memory Ray Tracing", IEEE TVCG 20(6),
/// 2014; OSPRay's data-distributed mode). It counts what crosses the network, not time: how
/// many owners each ray visits.

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "base/bbox.h"
#include "core/backend.h"
#include "core/scene.h"

namespace rp {

/// A scene's triangles in `cells.size()` domains: disjoint boxes that together cover the
/// scene's bounds, and for each the scene of the triangles whose bounds reach into it (one
/// mesh, three vertices per triangle; a triangle across a cell wall is in both cells).
struct Domains {
  std::vector<Box3f> cells;
  std::vector<Scene> parts;
  uint64_t triangles = 0;  ///< triangles in all parts together (each scene triangle once or more)
};

/// Splits the bounds of `scene`'s triangles into `count` cells by recursive splits at the
/// median of the triangles' centroids along their longest axis (a k-d partition; `count` need
/// not be a power of two), so that cells hold equal numbers of centroids (within one), and
/// gives each cell the triangles reaching into it. Throws rp::Error when the scene holds
/// anything but triangle meshes or fewer triangles than `count`.
Domains split_domains(const Scene& scene, int count);

/// What following a batch of rays through the domains cost.
struct Traffic {
  uint64_t rays = 0;           ///< rays followed (those entering no cell included)
  uint64_t visits = 0;         ///< domains that traced a ray, summed over the rays
  uint64_t forwards = 0;       ///< rays sent from one owner to the next: visits after each ray's first
  uint64_t one_domain = 0;     ///< rays traced by exactly one domain
  uint64_t no_domain = 0;      ///< rays that enter no cell
  uint64_t max_visits = 0;     ///< the most domains one ray visited
  uint64_t hits = 0;           ///< rays that hit (closest) or are blocked (any hit)
  uint64_t disagreements = 0;  ///< rays whose answer differs from one backend over the whole scene (should be 0)
};

/// Follows `rays` through `domains` (with `backends[d]` built over domains.parts[d]): each ray
/// goes to the cells it passes through within [tnear, tfar], in order along it; each traces it
/// over the stretch of the ray inside its cell (widened by 2^-20 at both ends, so that a hit on
/// a cell wall is found), and the ray stops at the first cell that finds a hit (closest hit:
/// cells further along are beyond it) or blocks it (`any_hit`, shadow rays). `whole` is a
/// backend over the whole scene, whose answers the domains' must reproduce
/// (Traffic::disagreements).
Traffic follow_rays(const Domains& domains, std::span<const std::unique_ptr<Backend>> backends, const Backend& whole,
                    std::span<const Ray> rays, bool any_hit);

}  // namespace rp
