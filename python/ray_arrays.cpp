#include "python/ray_arrays.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <mutex>

#include "base/error.h"
#include "core/invalid_rays.h"
#include "python/interrupt.h"

namespace rp::python {

namespace {

/// Per-thread buffers of one chunk's records, allocated once per thread and reused.
struct ChunkBuffers {
  std::vector<Ray> rays = std::vector<Ray>(kParallelChunk);
  std::vector<Hit> hits = std::vector<Hit>(kParallelChunk);
  std::vector<uint32_t> masks = std::vector<uint32_t>(kParallelChunk);
};
ChunkBuffers& chunk_buffers() {
  thread_local ChunkBuffers buffers;
  return buffers;
}

/// The masks of rays [begin, begin + n), in this thread's buffer.
std::span<const uint32_t> chunk_masks(const RayArrays& rays, size_t begin, size_t n) {
  const std::span<uint32_t> masks(chunk_buffers().masks.data(), n);
  rays.gather_masks(begin, masks);
  return masks;
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
      __builtin_prefetch(&scene.meshes()[at.shape].triangles[at.local]);
    }
}
void prefetch_corners(const Scene& scene, std::span<const Hit> hits) noexcept {
  for (const Hit& h : hits)
    if (h.prim_id < scene.triangle_count()) {
      const PrimLocation at = scene.locate(h.prim_id);
      const MeshView& m = scene.meshes()[at.shape];
      for (const uint32_t v : m.triangles[at.local]) __builtin_prefetch(&m.positions[v]);
    }
}

}  // namespace

std::string shape_text(std::span<const py::ssize_t> shape) {
  std::string s = "(";
  for (size_t d = 0; d < shape.size(); ++d) s += (d ? ", " : "") + std::to_string(shape[d]);
  return s + (shape.size() == 1 ? ",)" : ")");
}

std::string shape_text(const py::array& a) { return shape_text(std::span(a.shape(), size_t(a.ndim()))); }

namespace {

/// `object` as a uint32 array: the object itself when it is one, else numpy's conversion of an
/// array of integers after checking that every value fits (a mask is bits: -1 or 2^32 is a
/// mistake, not a wrap). Throws rp::Error naming `what` otherwise.
py::array uint32_array(const char* what, const py::handle& object) {
  const py::array given = py::array::ensure(object);
  if (!given) throw py::type_error(cat(what, ": a ", Py_TYPE(object.ptr())->tp_name, " is not numbers numpy can make"));
  const char kind = given.dtype().kind();
  RP_CHECK(kind == 'i' || kind == 'u', what, ": dtype ", std::string(py::str(given.dtype())),
           " is not an integer type (a mask is 32 bits: uint32)");
  if (py::isinstance<py::array_t<uint32_t>>(given)) return given;
  if (given.size() > 0) {
    const py::int_ lo = given.attr("min")(), hi = given.attr("max")();
    const auto fits = [](const py::int_& v) { return v >= py::int_(0) && v <= py::int_(0xffffffffu); };
    RP_CHECK(fits(lo), what, ": ", std::string(py::repr(lo)), " is not a 32-bit mask (0 .. 0xffffffff)");
    RP_CHECK(fits(hi), what, ": ", std::string(py::repr(hi)), " is not a 32-bit mask (0 .. 0xffffffff)");
  }
  return py::array_t<uint32_t, py::array::forcecast>::ensure(given);
}

}  // namespace

RayArrays::RayArrays(const py::handle& origins, const py::handle& directions, const py::handle& tnear,
                     const py::handle& tfar, const py::handle& mask) {
  const bool packed = directions.is_none();  // one (..., 6) array: origins then directions
  const char* names[kInputs] = {packed ? "rays" : "origins", packed ? "rays" : "directions", "tnear", "tfar", "mask"};
  // Each input's leading shape, and its byte step along each of its leading axes.
  std::array<std::vector<py::ssize_t>, kInputs> lead, steps;
  const auto take = [&](int c, py::array a, int components) {
    Input& in = inputs_[size_t(c)];
    in.data = static_cast<const char*>(a.data());
    const py::ssize_t axes = a.ndim() - (components > 1);
    lead[size_t(c)].assign(a.shape(), a.shape() + axes);
    steps[size_t(c)].assign(a.strides(), a.strides() + axes);
    if (components > 1) in.component = a.strides(axes);
    in.array = std::move(a);
  };
  const auto vectors = [&](int c, const py::handle& object, py::ssize_t width, const char* form) {
    py::array a = numbers<float>(names[c], object);
    if (a.ndim() == 0 || a.shape(a.ndim() - 1) != width)
      throw Error(cat(names[c], ": shape ", shape_text(a), " is not ", form));
    take(c, std::move(a), 3);
  };
  if (packed) {
    vectors(kOrigins, origins, 6, "(..., 6): origin and direction (or give directions too)");
    inputs_[kDirections] = inputs_[kOrigins];
    inputs_[kDirections].data += 3 * inputs_[kOrigins].component;
    lead[kDirections] = lead[kOrigins];
    steps[kDirections] = steps[kOrigins];
  } else {
    vectors(kOrigins, origins, 3, "(..., 3)");
    vectors(kDirections, directions, 3, "(..., 3)");
  }
  take(kTnear, numbers<float>(names[kTnear], tnear), 1);
  take(kTfar, numbers<float>(names[kTfar], tfar), 1);
  has_mask_ = !mask.is_none();
  if (has_mask_) {
    take(kMask, uint32_array(names[kMask], mask), 1);
  } else {  // every ray sees every geometry: one value broadcast
    static const uint32_t kSeesAll = 0xffffffffu;
    inputs_[kMask].data = reinterpret_cast<const char*>(&kSeesAll);
  }

  // numpy's broadcasting over the leading shapes, aligned on their last axes; `from` names the
  // first input that gave each axis its size, for the message.
  size_t axes = 0;
  for (const auto& l : lead) axes = std::max(axes, l.size());
  RP_CHECK(axes <= size_t(kMaxRayAxes), names[kOrigins], ": more than ", kMaxRayAxes, " axes");
  shape_.assign(axes, 1);
  std::vector<int> from(axes, -1);
  for (int c = 0; c < kInputs; ++c) {
    const std::vector<py::ssize_t>& l = lead[size_t(c)];
    for (size_t j = 0; j < l.size(); ++j) {
      const size_t d = axes - l.size() + j;
      if (l[j] == 1) continue;
      if (from[d] < 0 || shape_[d] == 1) {
        shape_[d] = l[j];
        from[d] = c;
      } else if (shape_[d] != l[j]) {
        throw Error(cat(names[c], ": rays of shape ", shape_text(l), ", but ", names[from[d]], " has rays of shape ",
                        shape_text(lead[size_t(from[d])])));
      }
    }
  }
  size_ = 1;
  for (const py::ssize_t n : shape_) size_ *= size_t(n);

  // The walk: the leading shape without its size-1 axes, each input's step along each axis (0
  // where it is broadcast), and neighbouring axes merged where every input steps evenly across
  // them (an array in C order, or broadcast, makes one axis of the two).
  std::vector<size_t> walk;
  std::array<std::vector<ptrdiff_t>, kInputs> walk_steps;
  for (size_t d = 0; d < axes; ++d) {
    if (shape_[d] == 1) continue;
    const auto step_of = [&](int c) -> ptrdiff_t {
      const std::vector<py::ssize_t>& l = lead[size_t(c)];
      if (d < axes - l.size()) return 0;
      const size_t j = d - (axes - l.size());
      return l[j] == 1 ? 0 : steps[size_t(c)][j];
    };
    bool merge = !walk.empty();
    for (int c = 0; c < kInputs && merge; ++c)
      merge = walk_steps[size_t(c)].back() == step_of(c) * ptrdiff_t(shape_[d]);
    if (merge) {
      walk.back() *= size_t(shape_[d]);
      for (int c = 0; c < kInputs; ++c) walk_steps[size_t(c)].back() = step_of(c);
    } else {
      walk.push_back(size_t(shape_[d]));
      for (int c = 0; c < kInputs; ++c) walk_steps[size_t(c)].push_back(step_of(c));
    }
  }
  if (walk.empty()) {  // one ray: a walk of one step
    walk.push_back(1);
    for (auto& w : walk_steps) w.push_back(0);
  }
  walk_axes_ = int(walk.size());
  for (size_t d = 0; d < walk.size(); ++d) {
    walk_shape_[d] = walk[d];
    for (int c = 0; c < kInputs; ++c) inputs_[size_t(c)].step[d] = walk_steps[size_t(c)][d];
  }
}

template <typename F>
void RayArrays::walk(size_t begin, size_t n, const F& f) const noexcept {
  if (n == 0) return;
  const int last = walk_axes_ - 1;
  std::array<size_t, kMaxRayAxes> index;  // the multi-index of ray begin + k
  size_t rest = begin;
  for (int d = last; d >= 0; --d) {
    index[size_t(d)] = rest % walk_shape_[size_t(d)];
    rest /= walk_shape_[size_t(d)];
  }
  for (size_t k = 0; k < n;) {
    std::array<ptrdiff_t, kInputs> offset{};
    for (int c = 0; c < kInputs; ++c)
      for (int d = 0; d <= last; ++d)
        offset[size_t(c)] += ptrdiff_t(index[size_t(d)]) * inputs_[size_t(c)].step[size_t(d)];
    // A run along the last axis, then carry into the axes before it.
    const size_t run = std::min(n - k, walk_shape_[size_t(last)] - index[size_t(last)]);
    for (size_t r = 0; r < run; ++r, ++k) {
      f(k, offset);
      for (int c = 0; c < kInputs; ++c) offset[size_t(c)] += inputs_[size_t(c)].step[size_t(last)];
    }
    index[size_t(last)] += run;
    for (int d = last; d > 0 && index[size_t(d)] == walk_shape_[size_t(d)]; --d) {
      index[size_t(d)] = 0;
      ++index[size_t(d - 1)];
    }
  }
}

size_t RayArrays::gather(size_t begin, std::span<Ray> out) const noexcept {
  // numpy arrays may be unaligned: read the bytes.
  const auto read = [](const char* p) {
    float f;
    std::memcpy(&f, p, sizeof f);
    return f;
  };
  const auto vec3 = [&](const Input& in, ptrdiff_t offset) {
    const char* p = in.data + offset;
    return Vec3f{read(p), read(p + in.component), read(p + 2 * in.component)};
  };
  size_t invalid = 0;
  walk(begin, out.size(), [&](size_t k, const std::array<ptrdiff_t, kInputs>& offset) {
    Ray& r = out[k];
    r.org = vec3(inputs_[kOrigins], offset[kOrigins]);
    r.dir = vec3(inputs_[kDirections], offset[kDirections]);
    r.tnear = read(inputs_[kTnear].data + offset[kTnear]);
    r.tfar = read(inputs_[kTfar].data + offset[kTfar]);
    invalid += !valid_ray(r);
  });
  return invalid;
}

void RayArrays::gather_masks(size_t begin, std::span<uint32_t> out) const noexcept {
  walk(begin, out.size(), [&](size_t k, const std::array<ptrdiff_t, kInputs>& offset) {
    std::memcpy(&out[k], inputs_[kMask].data + offset[kMask], sizeof(uint32_t));
  });
}

std::vector<Ray> RayArrays::records(size_t& invalid) const {
  std::vector<Ray> rays(size_);
  std::atomic<size_t> bad = 0;
  for_each_chunk(size_, [&](size_t begin, size_t n) { bad += gather(begin, std::span(rays).subspan(begin, n)); });
  invalid = bad;
  return rays;
}

namespace {

/// `shape` followed by `trailing`.
std::vector<py::ssize_t> with(std::vector<py::ssize_t> shape, std::initializer_list<py::ssize_t> trailing) {
  shape.insert(shape.end(), trailing);
  return shape;
}

}  // namespace

HitArrays::HitArrays(const std::vector<py::ssize_t>& shape, bool normals, bool geometry)
    : t(shape),
      u(shape),
      v(shape),
      ng(normals ? with(shape, {3}) : std::vector<py::ssize_t>{0, 3}),
      prim_id(shape),
      instance_id(shape),
      geometry_id(geometry ? shape : std::vector<py::ssize_t>{0}),
      t_(t.mutable_data()),
      u_(u.mutable_data()),
      v_(v.mutable_data()),
      ng_(normals ? ng.mutable_data() : nullptr),
      prim_id_(prim_id.mutable_data()),
      instance_id_(instance_id.mutable_data()),
      geometry_id_(geometry ? geometry_id.mutable_data() : nullptr) {}

void HitArrays::store(const Scene& scene, size_t begin, std::span<const Ray> rays, std::span<const Hit> hits) noexcept {
  for (size_t k = 0; k < hits.size(); ++k) {
    const size_t i = begin + k;
    t_[i] = hits[k].t;
    prim_id_[i] = hits[k].prim_id;
    instance_id_[i] = hits[k].instance_id;
    u_[i] = hits[k].u;
    v_[i] = hits[k].v;
  }
  if (geometry_id_)
    for (size_t k = 0; k < hits.size(); ++k)
      geometry_id_[begin + k] = hits[k].hit() ? scene.geometry_of(hits[k].prim_id) : kInvalidId;
  if (ng_) store_normals(scene, begin, rays, hits);
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
  if (geometry_id_) d["geometry_id"] = geometry_id;
  if (ng_) d["ng"] = ng;
  return d;
}

InvalidRays parse_invalid(const std::string& policy) {
  if (policy == "warn") return InvalidRays::warn;
  if (policy == "raise") return InvalidRays::raise;
  RP_CHECK(policy == "miss", "invalid: '", policy, "' is not warn, raise or miss");
  return InvalidRays::miss;
}

void report_invalid(const char* call, InvalidRays policy, size_t invalid, size_t total) {
  if (invalid == 0 || policy == InvalidRays::miss) return;
  const std::string message = invalid_rays_message(call, invalid, total);
  if (policy == InvalidRays::raise) throw Error(message);
  if (PyErr_WarnEx(PyExc_RuntimeWarning, message.c_str(), 1) != 0) throw py::error_already_set();
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
  HitArrays out(rays.shape(), normals, true);
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
        if (rays.has_mask())
          backend.intersect(r, h, TraceOptions{.masks = chunk_masks(rays, begin, n), .filter = {}});
        else
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
  py::array_t<bool> out = rays.answer<bool>();
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
        if (rays.has_mask())
          backend.occluded(r, std::span(occluded + begin, n),
                           TraceOptions{.masks = chunk_masks(rays, begin, n), .filter = {}});
        else
          backend.occluded(r, std::span(occluded + begin, n), coherence);
      });
    });
  });
  invalid = bad;
  return out;
}

}  // namespace rp::python
