/// raypack.Backend's queries beyond intersect and occluded (core/queries.h, docs/queries.md):
/// closest points, distance, inside, signed distance, counts and every hit along rays.

#include "python/queries.h"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <atomic>
#include <limits>
#include <vector>

#include "base/error.h"
#include "core/queries.h"
#include "python/handles.h"
#include "python/interrupt.h"
#include "python/ray_arrays.h"
#include "python/text_signatures.h"

namespace rp::python {

namespace {

using namespace pybind11::literals;

/// Calls with at least this many points or rays run interruptibly (python/interrupt.h).
constexpr size_t kLongCall = size_t(1) << 16;

/// Query points of shape (..., 3), copied to records, and their leading shape: the shape every
/// answer starts with.
struct PointArrays {
  std::vector<Vec3f> points;
  std::vector<py::ssize_t> shape;

  explicit PointArrays(const py::handle& object) {
    const auto a = numbers<float, py::array::forcecast | py::array::c_style>("points", object);
    RP_CHECK(a.ndim() >= 1 && a.shape(a.ndim() - 1) == 3, "points: shape ", shape_text(a), " is not (..., 3)");
    shape.assign(a.shape(), a.shape() + a.ndim() - 1);
    const float* x = a.data();
    points.resize(size_t(a.size() / 3));
    for (size_t i = 0; i < points.size(); ++i) points[i] = {x[3 * i], x[3 * i + 1], x[3 * i + 2]};
  }

  /// A new C-order array of T of shape shape() followed by `trailing`.
  template <typename T>
  py::array_t<T> answer(std::initializer_list<py::ssize_t> trailing = {}) const {
    std::vector<py::ssize_t> s = shape;
    s.insert(s.end(), trailing);
    return py::array_t<T>(s);
  }
};

/// Runs body(begin, n) over chunks of `n` items on `threads` threads, the GIL released and the
/// scene read-locked, interruptible when long.
void run_chunks(const BackendHandle& b, size_t n, int threads, const std::function<void(size_t, size_t)>& body) {
  interruptible(n >= kLongCall, [&](const std::atomic<bool>& stop) {
    const auto lock = reading(b.scene);
    with_threads(threads, [&] {
      for_each_chunk(n, [&](size_t begin, size_t count) {
        if (!stop.load(std::memory_order_relaxed)) body(begin, count);
      });
    });
  });
}

std::vector<ClosestPoint> closest(const BackendHandle& b, const PointArrays& p, float radius, int threads) {
  RP_CHECK(radius >= 0.0f, "radius: ", radius, " is not >= 0");
  std::vector<ClosestPoint> out(p.points.size());
  run_chunks(b, p.points.size(), threads, [&](size_t begin, size_t n) {
    std::vector<PointQuery> q(n);
    for (size_t i = 0; i < n; ++i) q[i] = {p.points[begin + i], radius};
    b.backend->closest_points(q, std::span(out).subspan(begin, n));
  });
  return out;
}

py::dict closest_points(const BackendHandle& b, const py::handle& points, float radius, int threads) {
  const PointArrays p(points);
  const std::vector<ClosestPoint> c = closest(b, p, radius, threads);
  py::array_t<float> where = p.answer<float>({3}), distance = p.answer<float>(), uv = p.answer<float>({2});
  py::array_t<uint32_t> prim = p.answer<uint32_t>(), geometry = p.answer<uint32_t>(), instance = p.answer<uint32_t>();
  float *w = where.mutable_data(), *d = distance.mutable_data(), *t = uv.mutable_data();
  uint32_t *pr = prim.mutable_data(), *g = geometry.mutable_data(), *in = instance.mutable_data();
  const Scene& s = *b.scene.scene;
  const auto lock = reading(b.scene);
  for (size_t i = 0; i < c.size(); ++i) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    w[3 * i] = c[i].found() ? c[i].point.x : nan;
    w[3 * i + 1] = c[i].found() ? c[i].point.y : nan;
    w[3 * i + 2] = c[i].found() ? c[i].point.z : nan;
    d[i] = c[i].distance;
    t[2 * i] = c[i].u;
    t[2 * i + 1] = c[i].v;
    pr[i] = c[i].prim_id;
    g[i] = c[i].found() ? s.geometry_of(c[i].prim_id) : kInvalidId;
    in[i] = c[i].instance_id;
  }
  return py::dict("points"_a = where, "distance"_a = distance, "prim_id"_a = prim, "geometry_id"_a = geometry,
                  "instance_id"_a = instance, "uv"_a = uv);
}

py::array_t<float> distance(const BackendHandle& b, const py::handle& points, int threads) {
  const PointArrays p(points);
  const std::vector<ClosestPoint> c = closest(b, p, std::numeric_limits<float>::infinity(), threads);
  py::array_t<float> out = p.answer<float>();
  for (size_t i = 0; i < c.size(); ++i) out.mutable_data()[i] = c[i].distance;
  return out;
}

py::array_t<float> signed_distances(const BackendHandle& b, const py::handle& points, int threads) {
  const PointArrays p(points);
  py::array_t<float> out = p.answer<float>();
  float* d = out.mutable_data();
  interruptible(p.points.size() >= kLongCall, [&](const std::atomic<bool>&) {
    const auto lock = reading(b.scene);
    with_threads(threads, [&] { signed_distance(*b.backend, p.points, std::span(d, p.points.size())); });
  });
  return out;
}

py::array_t<bool> inside_points(const BackendHandle& b, const py::handle& points, int threads) {
  const PointArrays p(points);
  py::array_t<bool> out = p.answer<bool>();
  uint8_t* in = reinterpret_cast<uint8_t*>(out.mutable_data());  // numpy's bool: one byte, 0 or 1
  interruptible(p.points.size() >= kLongCall, [&](const std::atomic<bool>&) {
    const auto lock = reading(b.scene);
    with_threads(threads, [&] { inside(*b.backend, p.points, std::span(in, p.points.size())); });
  });
  return out;
}

/// The rays of [begin, begin + n) and their masks (empty without a mask), gathered.
struct Chunk {
  std::vector<Ray> rays;
  std::vector<uint32_t> masks;
  size_t invalid = 0;
  Chunk(const RayArrays& r, size_t begin, size_t n) : rays(n), masks(r.has_mask() ? n : 0) {
    invalid = r.gather(begin, rays);
    if (r.has_mask()) r.gather_masks(begin, masks);
  }
};

py::array_t<uint32_t> count_intersections(const BackendHandle& b, const py::handle& origins,
                                          const py::handle& directions, const py::handle& tnear, const py::handle& tfar,
                                          const py::handle& mask, const std::string& invalid, int threads) {
  const InvalidRays policy = parse_invalid(invalid);
  const RayArrays rays(origins, directions, tnear, tfar, mask);
  py::array_t<uint32_t> out = rays.answer<uint32_t>();
  uint32_t* counts = out.mutable_data();
  std::atomic<size_t> bad = 0;
  run_chunks(b, rays.size(), threads, [&](size_t begin, size_t n) {
    const Chunk c(rays, begin, n);
    bad += c.invalid;
    b.backend->count_hits(c.rays, std::span(counts + begin, n), TraceOptions{.masks = c.masks, .filter = {}});
  });
  report_invalid("count_intersections", policy, bad, rays.size());
  return out;
}

py::dict all_hits(const BackendHandle& b, const py::handle& origins, const py::handle& directions,
                  const py::handle& tnear, const py::handle& tfar, size_t max_per_ray, const py::handle& mask,
                  const std::string& invalid, int threads) {
  const InvalidRays policy = parse_invalid(invalid);
  const RayArrays rays(origins, directions, tnear, tfar, mask);
  std::vector<HitList> lists((rays.size() + kParallelChunk - 1) / kParallelChunk);
  std::atomic<size_t> bad = 0;
  run_chunks(b, rays.size(), threads, [&](size_t begin, size_t n) {
    const Chunk c(rays, begin, n);
    bad += c.invalid;
    lists[begin / kParallelChunk] =
        b.backend->all_hits(c.rays, max_per_ray, TraceOptions{.masks = c.masks, .filter = {}});
  });
  report_invalid("all_hits", policy, bad, rays.size());
  size_t total = 0;
  for (const HitList& l : lists) total += l.hits.size();
  const auto n = py::ssize_t(total);
  py::array_t<int64_t> ray(n);
  py::array_t<float> t(n), u(n), v(n);
  py::array_t<uint32_t> prim(n), geometry(n), instance(n);
  const Scene& s = *b.scene.scene;
  const auto lock = reading(b.scene);
  size_t k = 0;
  for (size_t c = 0; c < lists.size(); ++c)
    for (size_t r = 0; r + 1 < lists[c].offsets.size(); ++r)
      for (const Hit& h : lists[c].of(r)) {
        ray.mutable_data()[k] = int64_t(c * kParallelChunk + r);
        t.mutable_data()[k] = h.t;
        u.mutable_data()[k] = h.u;
        v.mutable_data()[k] = h.v;
        prim.mutable_data()[k] = h.prim_id;
        geometry.mutable_data()[k] = s.geometry_of(h.prim_id);
        instance.mutable_data()[k] = h.instance_id;
        ++k;
      }
  return py::dict("ray"_a = ray, "t"_a = t, "prim_id"_a = prim, "geometry_id"_a = geometry, "instance_id"_a = instance,
                  "u"_a = u, "v"_a = v);
}

}  // namespace

void define_queries(py::module_& m) {
  py::reinterpret_borrow<py::class_<BackendHandle>>(m.attr("Backend"))
      .def("closest_points", &closest_points, "points"_a, py::kw_only(),
           py::arg_v("radius", std::numeric_limits<float>::infinity(), "math.inf"), "threads"_a = 0,
           "The closest point of the surface to each point (..., 3): a dict of points (..., 3; NaN where\n"
           "nothing is found), distance (...; inf), prim_id, geometry_id, instance_id (uint32; 0xffffffff)\n"
           "and uv (..., 2: a triangle's barycentrics, p = (1-u-v) v0 + u v1 + v v2). Nothing farther than\n"
           "radius is found. Triangles, spheres, polygons and planes; a scene with quadrics raises.")
      .def("distance", &distance, "points"_a, py::kw_only(), "threads"_a = 0,
           "Distance from each point (..., 3) to the surface: float32 (...), inf with no surface.")
      .def("signed_distance", &signed_distances, "points"_a, py::kw_only(), "threads"_a = 0,
           "Distance to the surface, negative inside (inside()): float32 (...).")
      .def("inside", &inside_points, "points"_a, py::kw_only(), "threads"_a = 0,
           "Whether each point (..., 3) is inside the closed surfaces: the majority of three rays'\n"
           "crossing parity (docs/queries.md says where it holds). bool (...).")
      .def("count_intersections", &count_intersections, "origins"_a, "directions"_a = py::none(), "tnear"_a = 0.0f,
           tfar_arg(), py::kw_only(), "mask"_a = py::none(), "invalid"_a = "warn", "threads"_a = 0,
           "How many surfaces each ray crosses within [tnear, tfar] (a sphere crossed twice counts 2):\n"
           "uint32 of the rays' leading shape. Rays and mask as intersect.")
      .def("all_hits", &all_hits, "origins"_a, "directions"_a = py::none(), "tnear"_a = 0.0f, tfar_arg(), py::kw_only(),
           "max_per_ray"_a = 0, "mask"_a = py::none(), "invalid"_a = "warn", "threads"_a = 0,
           "Every hit along each ray within [tnear, tfar]: a dict of flat arrays ray (int64, the ray's\n"
           "index in C order over the leading shape), t, prim_id, geometry_id, instance_id, u, v, sorted\n"
           "by ray then t; max_per_ray > 0 keeps each ray's nearest ones. Rays and mask as intersect.");
}

}  // namespace rp::python
