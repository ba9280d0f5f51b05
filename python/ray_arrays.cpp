#include "python/ray_arrays.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <mutex>

#include "base/error.h"
#include "python/interrupt.h"

namespace rp::python {

namespace {

/// Per-thread buffers of one chunk's records, allocated once per thread and reused.
struct ChunkBuffers {
  std::vector<Ray> rays = std::vector<Ray>(kParallelChunk);
  std::vector<Hit> hits = std::vector<Hit>(kParallelChunk);
};
ChunkBuffers& chunk_buffers() {
  thread_local ChunkBuffers buffers;
  return buffers;
}

/// Hits whose reads store() asks for at once (see prefetch_rows).
constexpr size_t kNormalGroup = 8;

/// Scene::surface reads, for a triangle hit, the triangle's index row and then its three
/// corners, scattered over the scene's arrays, which the backends do not read while tracing
/// (they trace their own copies): left alone, every hit's normal would wait for those reads
/// one after the other. So store() asks for them ahead, a group of hits at a time and two
/// stages deep: the index rows of the group after next (prefetch_rows), the corners of the
/// next group, whose rows have arrived by then (prefetch_corners), while it works out this
/// group's normals. Only hints: nothing computed depends on them.
void prefetch_rows(const Scene& scene, std::span<const Hit> hits) noexcept {
  for (const Hit& h : hits)
    if (h.prim_id < scene.triangle_count()) {
      const PrimLocation at = scene.locate(h.prim_id);
      __builtin_prefetch(&scene.meshes()[at.shape].indices[3 * size_t(at.local)]);
    }
}
void prefetch_corners(const Scene& scene, std::span<const Hit> hits) noexcept {
  for (const Hit& h : hits)
    if (h.prim_id < scene.triangle_count()) {
      const PrimLocation at = scene.locate(h.prim_id);
      const TriangleMesh& m = scene.meshes()[at.shape];
      for (size_t k = 0; k < 3; ++k) __builtin_prefetch(&m.positions[m.indices[3 * size_t(at.local) + k]]);
    }
}

}  // namespace

std::string shape_text(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t d = 0; d < a.ndim(); ++d) s += (d ? ", " : "") + std::to_string(a.shape(d));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

float Column::at(size_t i, int k) const noexcept {
  float f;  // numpy arrays may be unaligned: read the bytes
  std::memcpy(&f, data + ptrdiff_t(i) * row + k * component, sizeof f);
  return f;
}

RayArrays::RayArrays(const py::handle& origins, const py::handle& directions, const py::handle& tnear,
                     const py::handle& tfar) {
  static constexpr const char* kNames[4] = {"origins", "directions", "tnear", "tfar"};
  const py::handle inputs[4] = {origins, directions, tnear, tfar};
  int sized = -1;  // the first argument that is not broadcast
  for (int c = 0; c < 4; ++c) {
    const py::array_t<float, py::array::forcecast>& a = arrays_[size_t(c)] = numbers<float>(kNames[c], inputs[c]);
    Column& col = columns_[size_t(c)];
    col.data = reinterpret_cast<const char*>(a.data());
    size_t count = 1;
    if (c < 2) {
      if (a.ndim() == 1 && a.shape(0) == 3) {
        col.component = a.strides(0);
      } else if (a.ndim() == 2 && a.shape(1) == 3) {
        count = size_t(a.shape(0));
        col.row = a.strides(0);
        col.component = a.strides(1);
      } else {
        throw Error(cat(kNames[c], ": shape ", shape_text(a), " is not (N, 3) or (3,)"));
      }
    } else if (a.ndim() == 1) {
      count = size_t(a.shape(0));
      col.row = a.strides(0);
    } else if (a.ndim() != 0) {
      throw Error(cat(kNames[c], ": shape ", shape_text(a), " is not (N,) or a scalar"));
    }
    if (count == 1) {
      col.row = 0;  // one ray's values for every ray
    } else if (sized < 0) {
      sized = c;
      size_ = count;
    } else if (count != size_) {
      throw Error(cat(kNames[c], ": ", count, " rays, but ", kNames[sized], " has ", size_));
    }
  }
  if (sized < 0) size_ = 1;
}

size_t RayArrays::gather(size_t begin, std::span<Ray> out) const noexcept {
  const auto& [org, dir, tnear, tfar] = columns_;
  size_t invalid = 0;
  for (size_t k = 0; k < out.size(); ++k) {
    const size_t i = begin + k;
    Ray& r = out[k];
    r.org = org.vec3(i);
    r.dir = dir.vec3(i);
    r.tnear = tnear.at(i, 0);
    r.tfar = tfar.at(i, 0);
    invalid += !valid_ray(r);
  }
  return invalid;
}

std::vector<Ray> RayArrays::records(size_t& invalid) const {
  std::vector<Ray> rays(size_);
  std::atomic<size_t> bad = 0;
  for_each_chunk(size_, [&](size_t begin, size_t n) { bad += gather(begin, std::span(rays).subspan(begin, n)); });
  invalid = bad;
  return rays;
}

HitArrays::HitArrays(size_t n, bool normals)
    : t(py::ssize_t(n)), u(py::ssize_t(n)), v(py::ssize_t(n)), ng({py::ssize_t(normals ? n : 0), py::ssize_t(3)}),
      prim_id(py::ssize_t(n)), instance_id(py::ssize_t(n)), t_(t.mutable_data()), u_(u.mutable_data()),
      v_(v.mutable_data()), ng_(normals ? ng.mutable_data() : nullptr), prim_id_(prim_id.mutable_data()),
      instance_id_(instance_id.mutable_data()), normals_(normals) {}

void HitArrays::store(const Scene& scene, size_t begin, std::span<const Ray> rays, std::span<const Hit> hits) noexcept {
  for (size_t k = 0; k < hits.size(); ++k) {
    const size_t i = begin + k;
    t_[i] = hits[k].t;
    prim_id_[i] = hits[k].prim_id;
    instance_id_[i] = hits[k].instance_id;
    u_[i] = hits[k].u;
    v_[i] = hits[k].v;
  }
  if (normals_) store_normals(scene, begin, rays, hits);
}

void HitArrays::store_normals(const Scene& scene, size_t begin, std::span<const Ray> rays,
                              std::span<const Hit> hits) noexcept {
  const auto group = [&](size_t g) {  // hits [g G, (g + 1) G), empty past the end
    const size_t first = std::min(g * kNormalGroup, hits.size());
    return hits.subspan(first, std::min(kNormalGroup, hits.size() - first));
  };
  prefetch_rows(scene, group(0));
  prefetch_rows(scene, group(1));
  prefetch_corners(scene, group(0));
  for (size_t k = 0; k < hits.size(); ++k) {
    if (k % kNormalGroup == 0) {
      prefetch_rows(scene, group(k / kNormalGroup + 2));
      prefetch_corners(scene, group(k / kNormalGroup + 1));
    }
    const Vec3f n = hits[k].hit() ? scene.surface(rays[k], hits[k]).geometric_normal : Vec3f{};
    for (int a = 0; a < 3; ++a) ng_[3 * (begin + k) + size_t(a)] = n[a];
  }
}

py::dict HitArrays::to_dict() const {
  py::dict d;
  d["t"] = t;
  d["prim_id"] = prim_id;
  d["u"] = u;
  d["v"] = v;
  d["instance_id"] = instance_id;
  if (normals_) d["ng"] = ng;
  return d;
}

void with_threads(int threads, const std::function<void()>& f) {
  RP_CHECK(threads >= 0, "threads: ", threads, " is negative (0 uses every core)");
  if (threads == 0) return f();
  tbb::task_arena arena(threads);
  arena.execute(f);
}

namespace {

/// Calls with at least this many rays run interruptibly (python/interrupt.h): long enough that
/// a thread of their own costs nothing measurable.
constexpr size_t kLongCallRays = size_t(1) << 18;

}  // namespace

HitArrays trace_closest(const Backend& backend, const Scene& scene, std::shared_mutex& guard, const RayArrays& rays,
                        Coherence coherence, bool normals, int threads, size_t& invalid) {
  HitArrays out(rays.size(), normals);
  std::atomic<size_t> bad = 0;
  interruptible(rays.size() >= kLongCallRays, [&](const std::atomic<bool>& stop) {
    const std::shared_lock reading(guard);
    with_threads(threads, [&] {
      for_each_chunk(rays.size(), [&](size_t begin, size_t n) {
        if (stop.load(std::memory_order_relaxed)) return;
        ChunkBuffers& b = chunk_buffers();
        const std::span<Ray> r(b.rays.data(), n);
        const std::span<Hit> h(b.hits.data(), n);
        bad += rays.gather(begin, r);
        backend.intersect(r, h, coherence);
        out.store(scene, begin, r, h);
      });
    });
  });
  invalid = bad;
  return out;
}

py::array_t<bool> trace_any(const Backend& backend, std::shared_mutex& guard, const RayArrays& rays,
                            Coherence coherence, int threads, size_t& invalid) {
  py::array_t<bool> out(py::ssize_t(rays.size()));
  // numpy's bool is one byte holding 0 or 1, what Backend::occluded writes.
  uint8_t* const occluded = reinterpret_cast<uint8_t*>(out.mutable_data());
  std::atomic<size_t> bad = 0;
  interruptible(rays.size() >= kLongCallRays, [&](const std::atomic<bool>& stop) {
    const std::shared_lock reading(guard);
    with_threads(threads, [&] {
      for_each_chunk(rays.size(), [&](size_t begin, size_t n) {
        if (stop.load(std::memory_order_relaxed)) return;
        const std::span<Ray> r(chunk_buffers().rays.data(), n);
        bad += rays.gather(begin, r);
        backend.occluded(r, std::span(occluded + begin, n), coherence);
      });
    });
  });
  invalid = bad;
  return out;
}

}  // namespace rp::python
