#pragma once
/// The numpy side of tracing from Python: rays given as arrays, read where they lie, traced in
/// parallel chunks with the GIL released, hits written into numpy arrays.
///
/// What is copied. An input that is already float32 (any shape the call takes, any strides,
/// C-contiguous or not) is read in place; any other dtype (float64, integers, a Python list or
/// scalar) is converted once, by numpy, to a float32 array the call holds until it returns. The backend interface
/// takes Ray records (core/backend.h), so each chunk of kParallelChunk rays is gathered into
/// a per-thread buffer of records (32 bytes a ray, 128 KiB a thread, reused from call to call)
/// just before it is traced: no copy of the whole batch is ever made. Hits go from a per-thread
/// buffer of Hit records into the output arrays, which numpy owns from the start.

#include <pybind11/numpy.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
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
std::string shape_text(std::span<const py::ssize_t> shape);

/// The most axes a leading shape of rays may have: numpy's most of any array (NPY_MAXDIMS).
inline constexpr int kMaxRayAxes = 32;

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

/// The rays of one call, in the shapes Python users have, read where they lie. Either form:
/// - `origins` and `directions` of shape (..., 3): (N, 3), (H, W, 3), or (3,) for one point or
///   direction shared by every ray;
/// - `origins` alone of shape (..., 6), `directions` None: each ray's origin then direction
///   (Open3D's layout ox, oy, oz, dx, dy, dz), named `rays` in messages;
/// with `tnear`, `tfar` and `mask` scalars or arrays of the leading shape (...). The arguments'
/// leading shapes broadcast by numpy's rule (a (3,) origin for every ray, a tfar of shape (W,)
/// for every row of (H, W) rays) to the call's leading shape, shape(): the shape every answer
/// starts with (t (...), ng (..., 3)). The rays are numbered 0 .. size() - 1 in C order over
/// it, as the answers' elements are (answer<T>() allocates them).
///
/// What is read in place: float32 origins, directions, tnear and tfar and a uint32 mask, with
/// any strides (views, columns of a wider array, negative or zero strides); other dtypes are
/// converted once, by numpy, to arrays the object holds until it is destroyed.
///
/// Use, chunk by chunk as intersect does (trace_closest below), or the whole batch at once:
///   const RayArrays rays(origins, directions, tnear, tfar, mask);  // with the GIL
///   size_t invalid = 0;
///   const std::vector<Ray> flat = rays.records(invalid);           // C order over rays.shape()
///   std::vector<uint32_t> masks(rays.has_mask() ? rays.size() : 0);
///   rays.gather_masks(0, masks);                                   // empty: no mask given
///   py::array_t<uint32_t> counts = rays.answer<uint32_t>();         // of shape rays.shape()
///   backend.count_hits(flat, std::span(counts.mutable_data(), rays.size()),
///                      TraceOptions{.masks = masks, .filter = {}});
class RayArrays {
 public:
  /// Throws rp::Error with a one-line message naming the argument for a shape that is none of
  /// the above ("origins: shape (4, 2) is not (..., 3)"), leading shapes that do not broadcast
  /// ("directions: rays of shape (5,), but origins has rays of shape (4,)"), or a mask that is
  /// not integers in [0, 2^32); py::type_error for values that are not numbers.
  RayArrays(const py::handle& origins, const py::handle& directions, const py::handle& tnear, const py::handle& tfar,
            const py::handle& mask = py::none());

  size_t size() const { return size_; }
  /// The leading shape (...): () when every argument is one ray's.
  const std::vector<py::ssize_t>& shape() const { return shape_; }
  /// Whether a mask was given (without one every ray's mask is 0xffffffff: it sees everything).
  bool has_mask() const { return has_mask_; }

  /// Rays [begin, begin + out.size()) as records, into out; returns how many of them break the
  /// valid-ray rule (rp::valid_ray: NaN, infinite, out of range, tnear > tfar), which every
  /// backend reports as misses. Reads only the arrays: callable without the GIL.
  size_t gather(size_t begin, std::span<Ray> out) const noexcept;

  /// The masks of rays [begin, begin + out.size()), into out (0xffffffff for every ray when no
  /// mask was given). Callable without the GIL.
  void gather_masks(size_t begin, std::span<uint32_t> out) const noexcept;

  /// Every ray as records (what rp::Reference and rp::diff_hits take), gathered in parallel;
  /// `invalid` receives the count of rays that break the valid-ray rule.
  std::vector<Ray> records(size_t& invalid) const;

  /// A new C-order array of T, uninitialised, of shape shape() followed by `trailing`: an answer
  /// whose element (or row of `trailing` elements) i belongs to ray i. Needs the GIL.
  template <typename T>
  py::array_t<T> answer(std::initializer_list<py::ssize_t> trailing = {}) const {
    std::vector<py::ssize_t> shape = shape_;
    shape.insert(shape.end(), trailing);
    return py::array_t<T>(shape);
  }

 private:
  /// One argument as read: its array (held), and where component k of the ray at multi-index
  /// (i_0, .., i_d) of the walk lies: data + sum_j i_j * step[j] + k * component. A step is 0
  /// along an axis the argument is broadcast over.
  struct Input {
    py::array array;
    const char* data = nullptr;
    std::array<ptrdiff_t, kMaxRayAxes> step{};
    ptrdiff_t component = 0;
  };
  enum { kOrigins, kDirections, kTnear, kTfar, kMask, kInputs };

  /// Calls f(k, offsets) for rays begin + k, k in [0, n), with each input's byte offset of that
  /// ray, stepping along the walk's axes (the leading shape with its size-1 axes dropped and
  /// axes every input steps through evenly merged: one axis for arrays in C order).
  template <typename F>
  void walk(size_t begin, size_t n, const F& f) const noexcept;

  std::array<Input, kInputs> inputs_;
  std::vector<py::ssize_t> shape_;
  std::array<size_t, kMaxRayAxes> walk_shape_{};
  int walk_axes_ = 1;
  size_t size_ = 1;
  bool has_mask_ = false;
};

/// The tfar argument of a call that takes rays, "tfar"_a = +inf, its default written math.inf:
/// the spelling inspect.signature can evaluate (python/text_signatures.h).
inline py::arg_v tfar_arg() { return py::arg_v("tfar", std::numeric_limits<float>::infinity(), "math.inf"); }

/// What a call does with rays outside the valid-ray rule, which every backend reports as
/// misses (the `invalid` argument): warn (a RuntimeWarning naming how many: the line `raypack
/// trace` prints), raise (raypack.Error with that line) or miss (nothing more).
enum class InvalidRays : uint8_t { warn, raise, miss };

/// The policy named `policy` ("warn", "raise" or "miss"); throws rp::Error naming the argument
/// for another name.
InvalidRays parse_invalid(const std::string& policy);

/// Applies `policy` to a call (named `call` in the message) that found `invalid` of `total` rays
/// outside the rule: a warning (raising the warning's exception when warnings are errors), an
/// rp::Error, or nothing. Needs the GIL.
void report_invalid(const char* call, InvalidRays policy, size_t invalid, size_t total);

/// Closest hits as numpy arrays, one element per ray, each of the rays' leading shape (...):
/// t (float32, +inf on a miss), prim_id (uint32, 0xffffffff on a miss), u, v (float32, 0 on a
/// miss), instance_id (uint32, 0xffffffff on a miss and for a primitive placed by no instance),
/// geometry_id (uint32, Scene::geometry_of, 0xffffffff on a miss) and, unless left out, ng
/// (float32 (..., 3), the unit geometric normal as Scene::surface gives it, 0 on a miss): what
/// `raypack trace` writes to a hit file, field for field, and the geometry.
struct HitArrays {
  /// Allocates the arrays of leading shape `shape` (needs the GIL); ng only with `normals`,
  /// geometry_id only with `geometry` (a hit file's hits have no scene to ask).
  HitArrays(const std::vector<py::ssize_t>& shape, bool normals, bool geometry);

  /// Writes hits[k] of rays[k] at index begin + k (and its normal and geometry, when asked for).
  /// Writes only the arrays' memory: callable from any thread without the GIL, each on its own
  /// range.
  void store(const Scene& scene, size_t begin, std::span<const Ray> rays, std::span<const Hit> hits) noexcept;

  /// The arrays as the dict the Python module returns: keys t, prim_id, u, v, instance_id and,
  /// unless left out, geometry_id and ng.
  py::dict to_dict() const;

  py::array_t<float> t, u, v, ng;
  py::array_t<uint32_t> prim_id, instance_id, geometry_id;

 private:
  /// ng of every hit of store(), its reads asked for ahead (see ray_arrays.cpp).
  void store_normals(const Scene& scene, size_t begin, std::span<const Ray> rays, std::span<const Hit> hits) noexcept;

  /// The arrays' memory, taken while the GIL is held (store runs without it); ng_ and
  /// geometry_id_ are null when left out.
  float *t_, *u_, *v_, *ng_;
  uint32_t *prim_id_, *instance_id_, *geometry_id_;
};

/// Runs f() over `threads` TBB threads (0: all cores, as the command line's -t 0); throws
/// rp::Error for a negative count.
void with_threads(int threads, const std::function<void()>& f);

/// The closest hit of every ray through `backend` (built over `scene`), in chunks of
/// kParallelChunk rays over TBB's threads (rp::for_each_chunk, as rp::intersect_parallel cuts a
/// batch: the same backend calls, so the same bits), the GIL released and, for a long call,
/// stopped by Ctrl-C (python/interrupt.h); with `normals`, the
/// geometric normals too, holding `guard` shared (the scene's: changes of the scene and
/// backend updates hold it alone). Rays with masks (rays.has_mask()) see only the geometries
/// whose masks meet theirs (Backend::intersect with TraceOptions, ray by ray). Returns the hits
/// and sets `invalid` to the number of rays outside the valid-ray rule.
HitArrays trace_closest(const Backend& backend, const Scene& scene, std::shared_mutex& guard, const RayArrays& rays,
                        Coherence coherence, bool normals, int threads, size_t& invalid);

/// Any hit of every ray, as trace_closest: a bool array of the rays' leading shape, true where
/// the ray is occluded.
py::array_t<bool> trace_any(const Backend& backend, std::shared_mutex& guard, const RayArrays& rays,
                            Coherence coherence, int threads, size_t& invalid);

}  // namespace rp::python
