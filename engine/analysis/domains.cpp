#include "engine/analysis/domains.h"

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>

#include <algorithm>

#include "engine/error.h"
#include "engine/geometry/slab.h"

namespace rp {

namespace {

/// A triangle of the whole scene: its mesh, its index there, and its centroid.
struct Tri {
  uint32_t mesh, index;
  Vec3f centroid;
};

/// Splits tris[first, last) into `count` domains, appending each domain's triangles.
void split(std::vector<Tri>& tris, size_t first, size_t last, int count, std::vector<std::vector<Tri>>& out) {
  if (count == 1) {
    out.emplace_back(tris.begin() + std::ptrdiff_t(first), tris.begin() + std::ptrdiff_t(last));
    return;
  }
  Box3f box;
  for (size_t i = first; i < last; ++i) box.extend(tris[i].centroid);
  const Vec3f e = box.extent();
  const int axis = e.x >= e.y && e.x >= e.z ? 0 : e.y >= e.z ? 1 : 2;
  const int left = count / 2;
  const size_t middle = first + (last - first) * size_t(left) / size_t(count);
  std::nth_element(tris.begin() + std::ptrdiff_t(first), tris.begin() + std::ptrdiff_t(middle),
                   tris.begin() + std::ptrdiff_t(last),
                   [axis](const Tri& a, const Tri& b) { return a.centroid[axis] < b.centroid[axis]; });
  split(tris, first, middle, left, out);
  split(tris, middle, last, count - left, out);
}

}  // namespace

Domains split_domains(const Scene& scene, int count) {
  RP_CHECK(scene.prim_count() == scene.triangle_count(),
           "domains: the scene must hold triangle meshes only (it has analytic primitives or planes)");
  RP_CHECK(count >= 1 && uint32_t(count) <= scene.triangle_count(), "domains: ", count, " domains for ",
           scene.triangle_count(), " triangles");
  std::vector<Tri> tris;
  tris.reserve(scene.triangle_count());
  for (uint32_t m = 0; m < scene.meshes().size(); ++m) {
    const TriangleMesh& mesh = scene.meshes()[m];
    for (uint32_t t = 0; t < mesh.triangle_count(); ++t)
      tris.push_back({m, t, (mesh.vertex(t, 0) + mesh.vertex(t, 1) + mesh.vertex(t, 2)) * (1.0f / 3.0f)});
  }
  std::vector<std::vector<Tri>> groups;
  split(tris, 0, tris.size(), count, groups);
  Domains d;
  for (const std::vector<Tri>& group : groups) {
    TriangleMesh part;
    part.name = "domain";
    Box3f bounds;
    for (const Tri& t : group)
      for (int k = 0; k < 3; ++k) {
        const Vec3f p = scene.meshes()[t.mesh].vertex(t.index, k);
        part.indices.push_back(uint32_t(part.positions.size()));
        part.positions.push_back(p);
        bounds.extend(p);
      }
    Scene s;
    s.add_mesh(std::move(part));
    d.parts.push_back(std::move(s));
    d.bounds.push_back(bounds);
  }
  return d;
}

Traffic follow_rays(const Domains& domains, std::span<const std::unique_ptr<Backend>> backends, const Backend& whole,
                    std::span<const Ray> rays, bool any_hit) {
  RP_CHECK(backends.size() == domains.parts.size(), "domains: ", backends.size(), " backends for ",
           domains.parts.size(), " domains");
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
      float t;
      size_t domain;
    };
    std::vector<Entry> order;
    for (size_t i = range.begin(); i < range.end(); ++i) {
      // The domains the ray enters, nearest entry first.
      Ray ray = rays[i];
      order.clear();
      if (valid_ray(ray))
        for (size_t d = 0; d < domains.bounds.size(); ++d)
          if (const SlabHit<float> h = intersect_box(ray, domains.bounds[d]); h.hit)
            order.push_back({std::max(h.t_enter, ray.tnear), d});
      std::sort(order.begin(), order.end(),
                [](const Entry& a, const Entry& b) { return a.t < b.t || (a.t == b.t && a.domain < b.domain); });
      uint64_t visits = 0;
      bool blocked = false;
      Hit best;
      for (const Entry& e : order) {
        if (blocked || e.t > ray.tfar) break;  // found, or nearer than every domain left
        ++visits;
        if (any_hit) {
          uint8_t b = 0;
          backends[e.domain]->occluded({&ray, 1}, {&b, 1}, Coherence::incoherent);
          blocked = b != 0;
        } else {
          Hit h;
          backends[e.domain]->intersect({&ray, 1}, {&h, 1}, Coherence::incoherent);
          if (h.hit()) {
            best = h;
            ray.tfar = h.t;  // what the next owner is sent: the ray, its closest hit so far as tfar
          }
        }
      }
      ++t.rays;
      t.visits += visits;
      t.forwards += visits > 0 ? visits - 1 : 0;
      t.one_domain += visits == 1;
      t.no_domain += order.empty();
      t.max_visits = std::max(t.max_visits, visits);
      const bool hit = any_hit ? blocked : best.hit();
      t.hits += hit;
      t.disagreements += any_hit ? blocked != (want_blocked[i] != 0) : hit != want[i].hit() || (hit && best.t != want[i].t);
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
