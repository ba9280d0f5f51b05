#include "core/backend.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>

#include "base/error.h"
#include "core/geometry/closest_point.h"
#include "core/geometry/plane.h"

namespace rp {

UpdateReport Backend::update() {
  if (current()) return {};
  const auto start = std::chrono::steady_clock::now();
  UpdateReport r = apply_changes(version_);
  version_ = scene_->version();
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

void Backend::throw_stale() const {
  throw Error(cat(info().name, "/", info().variant, ": the scene changed since this backend was built or updated (",
                  scene_->version() - version_, " change", scene_->version() - version_ == 1 ? "" : "s",
                  ", the last: ", scene_->last_change(), "); call update() before tracing"));
}

namespace {

/// The planes' hits of valid ray `r` (index i) within [tnear, tfar] that `accepts` lets
/// through, each as f(hit), in plane order.
template <class Accepts, class F>
void each_plane_hit(const Scene& scene, const Ray& r, Accepts&& accepts, F&& f) {
  for (uint32_t k = 0; k < scene.planes().size(); ++k) {
    const Plane& p = scene.planes()[k];
    const Intersection<float> h = intersect_plane(r, p.normal, p.d);
    if (h.hit) {
      const Hit hit{h.t, scene.plane_base() + k, h.u, h.v, kNoInstance};
      if (accepts(hit)) f(hit);
    }
  }
}

/// Orders hits by (t, prim_id, instance_id).
bool hit_before(const Hit& a, const Hit& b) {
  if (a.t != b.t) return a.t < b.t;
  if (a.prim_id != b.prim_id) return a.prim_id < b.prim_id;
  return a.instance_id < b.instance_id;
}

bool same_hit(const Hit& a, const Hit& b) {
  return a.t == b.t && a.prim_id == b.prim_id && a.instance_id == b.instance_id;
}

}  // namespace

void Backend::intersect(std::span<const Ray> rays, std::span<Hit> hits, const TraceOptions& options) const {
  if (!current()) throw_stale();
  trace_closest_filtered(rays, hits, options);
  if (scene_->planes().empty()) return;
  for (size_t i = 0; i < rays.size(); ++i) {
    if (!valid_ray(rays[i])) continue;
    // As Scene::intersect_planes: a plane takes a hit at equal t.
    each_plane_hit(*scene_, rays[i], gate(options, rays[i], i), [&](const Hit& h) {
      if (h.t <= hits[i].t) hits[i] = h;
    });
  }
}

void Backend::occluded(std::span<const Ray> rays, std::span<uint8_t> occluded, const TraceOptions& options) const {
  if (!current()) throw_stale();
  trace_any_filtered(rays, occluded, options);
  if (scene_->planes().empty()) return;
  for (size_t i = 0; i < rays.size(); ++i)
    if (!occluded[i] && valid_ray(rays[i]))
      each_plane_hit(*scene_, rays[i], gate(options, rays[i], i), [&](const Hit&) { occluded[i] = 1; });
}

HitList Backend::all_hits(std::span<const Ray> rays, size_t max_per_ray, const TraceOptions& options) const {
  if (!current()) throw_stale();
  HitList list;
  list.offsets.reserve(rays.size() + 1);
  list.offsets.push_back(0);
  std::vector<Hit> found;
  for (size_t i = 0; i < rays.size(); ++i) {
    found.clear();
    if (valid_ray(rays[i])) {
      trace_every(rays, i, options, found);
      each_plane_hit(*scene_, rays[i], gate(options, rays[i], i), [&](const Hit& h) { found.push_back(h); });
      std::sort(found.begin(), found.end(), hit_before);
      found.erase(std::unique(found.begin(), found.end(), same_hit), found.end());
      if (max_per_ray && found.size() > max_per_ray) found.resize(max_per_ray);
    }
    list.hits.insert(list.hits.end(), found.begin(), found.end());
    list.offsets.push_back(list.hits.size());
  }
  return list;
}

void Backend::count_hits(std::span<const Ray> rays, std::span<uint32_t> counts, const TraceOptions& options) const {
  RP_CHECK(counts.size() == rays.size(), "count_hits: ", counts.size(), " counts for ", rays.size(), " rays");
  const HitList list = all_hits(rays, 0, options);
  for (size_t i = 0; i < rays.size(); ++i) counts[i] = uint32_t(list.count(i));
}

void Backend::closest_points(std::span<const PointQuery> queries, std::span<ClosestPoint> out) const {
  if (!current()) throw_stale();
  RP_CHECK(out.size() == queries.size(), "closest_points: ", out.size(), " answers for ", queries.size(), " points");
  RP_CHECK(scene_->quadrics().empty(), info().name, ": closest points: the scene has ", scene_->quadrics().size(),
           " quadric", scene_->quadrics().size() == 1 ? "" : "s", " (quadrics have no closest-point routine)");
  closest_points_of(queries, out);
  for (size_t i = 0; i < queries.size(); ++i) {
    const PointQuery& q = queries[i];
    if (!valid_point_query(q)) continue;
    for (uint32_t k = 0; k < scene_->planes().size(); ++k) {
      const Plane& p = scene_->planes()[k];
      const Vec3f c = closest_on_plane(q.point, p.normal, p.d);
      const float d = length(c - q.point);
      // Planes come last in the numbering: an equally close primitive keeps the point.
      if (d <= q.radius && d < out[i].distance) out[i] = {c, d, scene_->plane_base() + k, kNoInstance, 0.0f, 0.0f};
    }
  }
}

void for_each_chunk(size_t n, const std::function<void(size_t begin, size_t count)>& body) {
  tbb::parallel_for(size_t(0), (n + kParallelChunk - 1) / kParallelChunk, [&](size_t c) {
    const size_t begin = c * kParallelChunk;
    body(begin, std::min(kParallelChunk, n - begin));
  });
}

void intersect_parallel(const Backend& backend, std::span<const Ray> rays, std::span<Hit> hits, Coherence coherence) {
  for_each_chunk(rays.size(), [&](size_t begin, size_t n) {
    backend.intersect(rays.subspan(begin, n), hits.subspan(begin, n), coherence);
  });
}

void occluded_parallel(const Backend& backend, std::span<const Ray> rays, std::span<uint8_t> occluded,
                       Coherence coherence) {
  for_each_chunk(rays.size(), [&](size_t begin, size_t n) {
    backend.occluded(rays.subspan(begin, n), occluded.subspan(begin, n), coherence);
  });
}

void count_hits_parallel(const Backend& backend, std::span<const Ray> rays, std::span<uint32_t> counts) {
  for_each_chunk(rays.size(),
                 [&](size_t begin, size_t n) { backend.count_hits(rays.subspan(begin, n), counts.subspan(begin, n)); });
}

HitList all_hits_parallel(const Backend& backend, std::span<const Ray> rays) {
  std::vector<HitList> chunks((rays.size() + kParallelChunk - 1) / kParallelChunk);
  for_each_chunk(rays.size(), [&](size_t begin, size_t n) {
    chunks[begin / kParallelChunk] = backend.all_hits(rays.subspan(begin, n));
  });
  HitList all;
  all.offsets.reserve(rays.size() + 1);
  all.offsets.push_back(0);
  for (const HitList& c : chunks) {
    for (size_t i = 1; i < c.offsets.size(); ++i) all.offsets.push_back(all.hits.size() + c.offsets[i]);
    all.hits.insert(all.hits.end(), c.hits.begin(), c.hits.end());
  }
  return all;
}

}  // namespace rp
