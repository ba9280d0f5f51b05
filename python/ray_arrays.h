#pragma once
/// The numpy side of tracing from Python: rays given as arrays, read where they lie, traced in
/// parallel chunks with the GIL released, hits written into numpy arrays.
///
/// What is copied. An input that is already float32 (any strides, C-contiguous or not) is
/// read in place; any other dtype (float64, integers, a Python list or scalar) is converted
/// once, by numpy, to a float32 array the call holds until it returns. The backend interface
/// takes Ray records (core/backend.h), so each chunk of kParallelChunk rays is gathered into
/// a per-thread buffer of records (32 bytes a ray, 128 KiB a thread, reused from call to call)
/// just before it is traced: no copy of the whole batch is ever made. Hits go from a per-thread
/// buffer of Hit records into the output arrays, which numpy owns from the start.

#include <pybind11/numpy.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <shared_mutex>
#include <span>
#include <string>

#include "core/backend.h"
#include "core/ray.h"
#include "core/scene.h"

namespace rp::python {

namespace py = pybind11;

/// numpy's spelling of an array's shape: (4, 2), (4,), ().
std::string shape_text(const py::array& a);

/// `object` as a numpy array of T: the object itself when it already is one (with the layout
/// Flags asks for: any strides with py::array::forcecast alone, C order with c_style too), else
/// a converted copy numpy makes. Throws py::type_error naming `what` when numpy cannot make
/// numbers of it.
template <typename T, int Flags = py::array::forcecast>
py::array_t<T, Flags> numbers(const char* what, const py::handle& object) {
  auto a = py::array_t<T, Flags>::ensure(object);
  if (!a)
    throw py::type_error(std::string(what) + ": a " + Py_TYPE(object.ptr())->tp_name + " is not numbers numpy can make " +
                         std::string(py::str(py::dtype::of<T>())));
  return a;
}

/// One float32 input column of a batch: component k of ray i at data + i * row + k * component
/// bytes. row == 0 gives every ray the same value (a broadcast scalar or (3,) vector).
struct Column {
  const char* data = nullptr;
  ptrdiff_t row = 0, component = 0;

  float at(size_t i, int k) const noexcept;
  Vec3f vec3(size_t i) const noexcept { return {at(i, 0), at(i, 1), at(i, 2)}; }
};

/// The rays of one call: origins and directions of shape (N, 3), (1, 3) or (3,), tnear and
/// tfar of shape (N,), (1,) or scalars; the arrays of size 1 are broadcast to every ray, and
/// N is 1 when all of them are. Holds the arrays (the caller's own when they are float32)
/// until it is destroyed.
class RayArrays {
 public:
  /// Throws rp::Error with a one-line message naming the argument for a shape that is none of
  /// the above or a ray count that differs from another argument's, py::type_error for values
  /// that are not numbers.
  RayArrays(const py::handle& origins, const py::handle& directions, const py::handle& tnear, const py::handle& tfar);

  size_t size() const { return size_; }

  /// Rays [begin, begin + out.size()) as records, into out; returns how many of them break the
  /// valid-ray rule (rp::valid_ray: NaN, infinite, out of range, tnear > tfar), which every
  /// backend reports as misses. Reads only the arrays: callable without the GIL.
  size_t gather(size_t begin, std::span<Ray> out) const noexcept;

  /// Every ray as records (what rp::Reference and rp::diff_hits take), gathered in parallel;
  /// `invalid` receives the count of rays that break the valid-ray rule.
  std::vector<Ray> records(size_t& invalid) const;

 private:
  std::array<py::array_t<float, py::array::forcecast>, 4> arrays_;  ///< float32: the caller's own, else copies
  std::array<Column, 4> columns_;  ///< origins, directions, tnear, tfar
  size_t size_ = 0;
};

/// Closest hits as numpy arrays, one element per ray: t (float32, +inf on a miss), prim_id
/// (uint32, 0xffffffff on a miss), u, v (float32, 0 on a miss), instance_id (uint32,
/// 0xffffffff on a miss and for a primitive placed by no instance) and, unless left out, ng
/// (float32 (N, 3), the unit geometric normal as Scene::surface gives it, 0 on a miss): what
/// `raypack trace` writes to a hit file, field for field.
struct HitArrays {
  /// Allocates the arrays (needs the GIL); ng only with `normals`.
  HitArrays(size_t n, bool normals);

  /// Writes hits[k] of rays[k] at index begin + k (and its normal, when asked for). Writes only
  /// the arrays' memory: callable from any thread without the GIL, each on its own range.
  void store(const Scene& scene, size_t begin, std::span<const Ray> rays, std::span<const Hit> hits) noexcept;

  /// The arrays as the dict the Python module returns: keys t, prim_id, u, v, instance_id and,
  /// unless left out, ng.
  py::dict to_dict() const;

  py::array_t<float> t, u, v, ng;
  py::array_t<uint32_t> prim_id, instance_id;

 private:
  /// ng of every hit of store(), its reads asked for ahead (see ray_arrays.cpp).
  void store_normals(const Scene& scene, size_t begin, std::span<const Ray> rays, std::span<const Hit> hits) noexcept;

  /// The arrays' memory, taken while the GIL is held (store runs without it); ng_ is null
  /// when the normals are left out (normals_ false).
  float *t_, *u_, *v_, *ng_;
  uint32_t *prim_id_, *instance_id_;
  bool normals_;
};

/// Runs f() over `threads` TBB threads (0: all cores, as the command line's -t 0); throws
/// rp::Error for a negative count.
void with_threads(int threads, const std::function<void()>& f);

/// The closest hit of every ray through `backend` (built over `scene`), in chunks of
/// kParallelChunk rays over TBB's threads (rp::for_each_chunk, as rp::intersect_parallel cuts a
/// batch: the same backend calls, so the same bits), the GIL released and, for a long call,
/// stopped by Ctrl-C (python/interrupt.h); with `normals`, the
/// geometric normals too, holding `guard` shared (the scene's: changes of the scene and
/// backend updates hold it alone). Returns the hits and sets `invalid` to the number of rays
/// outside the valid-ray rule.
HitArrays trace_closest(const Backend& backend, const Scene& scene, std::shared_mutex& guard, const RayArrays& rays,
                        Coherence coherence, bool normals, int threads, size_t& invalid);

/// Any hit of every ray, as trace_closest: a bool array, true where the ray is occluded.
py::array_t<bool> trace_any(const Backend& backend, std::shared_mutex& guard, const RayArrays& rays,
                            Coherence coherence, int threads, size_t& invalid);

}  // namespace rp::python
