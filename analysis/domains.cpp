#include "analysis/domains.h"

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>

#include <algorithm>

#include "base/error.h"
#include "core/geometry/slab.h"

namespace rp {

namespace {

/// A triangle of the whole scene: its mesh, its index there, its centroid and its bounds.
struct Tri {
  uint32_t mesh, index;
  Vec3f centroid;
  Box3f bounds;
};

/// Splits `cell` into `count` cells at the median centroid of tris[first, last) (the triangles
/// whose centroids lie in it), appending the cells in order.
void split(std::vector<Tri>& tris, size_t first, size_t last, const Box3f& cell, int count, std::vector<Box3f>& out) {
  if (count == 1) {
    out.push_back(cell);
    return;
  }
  Box3f centroids;
  for (size_t i = first; i < last; ++i) centroids.extend(tris[i].centroid);
  const Vec3f e = centroids.extent();
  const int axis = e.x >= e.y && e.x >= e.z ? 0 : e.y >= e.z ? 1 : 2;
  const int left = count / 2;
  const size_t middle = first + (last - first) * size_t(left) / size_t(count);
  std::nth_element(tris.begin() + std::ptrdiff_t(first), tris.begin() + std::ptrdiff_t(middle),
                   tris.begin() + std::ptrdiff_t(last),
                   [axis](const Tri& a, const Tri& b) { return a.centroid[axis] < b.centroid[axis]; });
  const float plane = std::clamp(tris[middle].centroid[axis], cell.lo[axis], cell.hi[axis]);
  Box3f lo = cell, hi = cell;
  lo.hi[axis] = plane;
  hi.lo[axis] = plane;
  split(tris, first, middle, lo, left, out);
  split(tris, middle, last, hi, count - left, out);
}

bool overlap(const Box3f& a, const Box3f& b) {
  for (int k = 0; k < 3; ++k)
    if (a.hi[k] < b.lo[k] || b.hi[k] < a.lo[k]) return false;
  return true;
}

/// The ray parameter `t` moved outwards by 2^-20 of its size (towards lower values when `down`).
float widen(float t, bool down) {
  const float pad = std::abs(t) * 0x1.0p-20f;
  return down ? t - pad : t + pad;
}

}  // namespace

Domains split_domains(const Scene& scene, int count) {
  RP_CHECK(scene.prim_count() == scene.triangle_count(),
           "domains: the scene must hold triangle meshes only (it has analytic primitives or planes)");
  RP_CHECK(count >= 1 && uint32_t(count) <= scene.triangle_count(), "domains: ", count, " domains for ",
           scene.triangle_count(), " triangles");
  std::vector<Tri> tris;
  tris.reserve(scene.triangle_count());
  Box3f all;
  for (uint32_t m = 0; m < scene.meshes().size(); ++m) {
    const MeshView& mesh = scene.meshes()[m];
    for (uint32_t t = 0; t < mesh.triangle_count(); ++t) {
      Tri tri{m, t, (mesh.vertex(t, 0) + mesh.vertex(t, 1) + mesh.vertex(t, 2)) * (1.0f / 3.0f), {}};
      for (int k = 0; k < 3; ++k) tri.bounds.extend(mesh.vertex(t, k));
      all.extend(tri.bounds);
      tris.push_back(tri);
    }
  }
  Domains d;
  split(tris, 0, tris.size(), all, count, d.cells);
  for (const Box3f& cell : d.cells) {
    TriangleMesh part;
    part.name = "domain";
    for (const Tri& t : tris) {
      if (!overlap(t.bounds, cell)) continue;
      for (int k = 0; k < 3; ++k) {
        part.indices.push_back(uint32_t(part.positions.size()));
        part.positions.push_back(scene.meshes()[t.mesh].vertex(t.index, k));
      }
    }
    d.triangles += part.triangle_count();
    Scene s;
    s.add_mesh(std::move(part));
    d.parts.push_back(std::move(s));
  }
  return d;
}

Traffic follow_rays(const Domains& domains, std::span<const std::unique_ptr<Backend>> backends, const Backend& whole,
                    std::span<const Ray> rays, bool any_hit) {
  RP_CHECK(backends.size() == domains.cells.size(), "domains: ", backends.size(), " backends for ",
           domains.cells.size(), " domains");
  // The whole scene's answers, for the check.
  std::vector<Hit> want(rays.size());
  std::vector<uint8_t> want_blocked(rays.size());
  if (any_hit)
    occluded_parallel(whole, rays, want_blocked, Coherence::incoherent);
  else
    intersect_parallel(whole, rays, want, Coherence::incoherent);
  tbb::combinable<Traffic> traffic;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.size(), 1024), [&](const tbb::blocked_range<size_t>& range) {
    Traffic& t = traffic.local();
    struct Entry {
      float enter, exit;
      size_t domain;
    };
    std::vector<Entry> order;
    for (size_t i = range.begin(); i < range.end(); ++i) {
      // The cells the ray passes through, in order along it, with its stretch in each.
      const Ray& ray = rays[i];
      order.clear();
      if (valid_ray(ray))
        for (size_t d = 0; d < domains.cells.size(); ++d)
          if (const SlabHit<float> h = intersect_box(ray, domains.cells[d]); h.hit)
            order.push_back({std::max(h.t_enter, ray.tnear), std::min(h.t_exit, ray.tfar), d});
      std::sort(order.begin(), order.end(),
                [](const Entry& a, const Entry& b) { return a.enter < b.enter || (a.enter == b.enter && a.domain < b.domain); });
      uint64_t visits = 0;
      bool found = false;
      Hit best;
      for (const Entry& e : order) {
        ++visits;
        Ray stretch = ray;
        stretch.tnear = std::max(ray.tnear, widen(e.enter, true));
        stretch.tfar = std::min(ray.tfar, widen(e.exit, false));
        if (any_hit) {
          uint8_t b = 0;
          backends[e.domain]->occluded({&stretch, 1}, {&b, 1}, Coherence::incoherent);
          found = b != 0;
        } else {
          backends[e.domain]->intersect({&stretch, 1}, {&best, 1}, Coherence::incoherent);
          found = best.hit();
        }
        if (found) break;  // the cells further along lie beyond this hit
      }
      ++t.rays;
      t.visits += visits;
      t.forwards += visits > 0 ? visits - 1 : 0;
      t.one_domain += visits == 1;
      t.no_domain += order.empty();
      t.max_visits = std::max(t.max_visits, visits);
      t.hits += found;
      t.disagreements += any_hit ? found != (want_blocked[i] != 0) : found != want[i].hit() || (found && best.t != want[i].t);
    }
  });
  Traffic total;
  traffic.combine_each([&](const Traffic& t) {
    total.rays += t.rays;
    total.visits += t.visits;
    total.forwards += t.forwards;
    total.one_domain += t.one_domain;
    total.no_domain += t.no_domain;
    total.max_visits = std::max(total.max_visits, t.max_visits);
    total.hits += t.hits;
    total.disagreements += t.disagreements;
  });
  return total;
}

}  // namespace rp
