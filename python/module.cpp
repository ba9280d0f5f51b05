// The compiled part of the Python package `raypack` (python/raypack/__init__.py re-exports it):
// backends by name, closest and any hits over numpy arrays, camera rays, the renderer, the diff
// and ray and hit files. Scenes are scene.cpp's, the numpy side of tracing ray_arrays.{h,cpp},
// who owns what and the scene's lock handles.h.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <array>
#include <filesystem>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <shared_mutex>
#include <string>
#include <variant>

#include "analysis/diff.h"
#include "analysis/raygen.h"
#include "analysis/reference.h"
#include "backends/registry.h"
#include "base/error.h"
#include "io/rayfile.h"
#include "python/handles.h"
#include "python/interrupt.h"
#include "python/queries.h"
#include "python/ray_arrays.h"
#include "python/scene.h"
#include "python/text_signatures.h"
#include "render/camera.h"
#include "render/image_io.h"
#include "render/render.h"

namespace rp::python {
namespace {

using namespace pybind11::literals;

BackendHandle build(const std::string& name, const SceneHandle& scene, const std::string& variant,
                    const std::string& coherent_method, const std::string& incoherent_method, double refit_limit) {
  BackendOptions options;
  options.variant = variant;
  options.coherent_method = coherent_method;
  options.incoherent_method = incoherent_method;
  options.refit_limit = refit_limit;
  py::gil_scoped_release release;
  const auto lock = reading(scene);
  return {scene, make_backend(name, std::shared_ptr<const Scene>(scene.scene), options)};
}

py::dict intersect(const BackendHandle& b, const py::handle& origins, const py::handle& directions,
                   const py::handle& tnear, const py::handle& tfar, bool coherent, const py::handle& mask,
                   const std::string& invalid, bool normals, int threads) {
  const InvalidRays policy = parse_invalid(invalid);
  const RayArrays rays(origins, directions, tnear, tfar, mask);
  size_t bad = 0;
  const HitArrays hits = trace_closest(*b.backend, *b.scene.scene, *b.scene.guard, rays,
                                       coherent ? Coherence::coherent : Coherence::incoherent, normals, threads, bad);
  report_invalid("intersect", policy, bad, rays.size());
  return hits.to_dict();
}

py::array_t<bool> occluded(const BackendHandle& b, const py::handle& origins, const py::handle& directions,
                           const py::handle& tnear, const py::handle& tfar, bool coherent, const py::handle& mask,
                           const std::string& invalid, int threads) {
  const InvalidRays policy = parse_invalid(invalid);
  const RayArrays rays(origins, directions, tnear, tfar, mask);
  size_t bad = 0;
  py::array_t<bool> out =
      trace_any(*b.backend, *b.scene.guard, rays, coherent ? Coherence::coherent : Coherence::incoherent, threads, bad);
  report_invalid("occluded", policy, bad, rays.size());
  return out;
}

/// Rays as the dict every ray function returns and intersect(**rays) takes: origins and
/// directions (..., 3), tnear and tfar (...), float32, of leading shape `shape` ((N,) unless
/// given; its product is rays.size()).
py::dict ray_dict(std::span<const Ray> rays, std::vector<py::ssize_t> shape = {}) {
  if (shape.empty()) shape = {py::ssize_t(rays.size())};
  std::vector<py::ssize_t> vectors = shape;
  vectors.push_back(3);
  py::array_t<float> org(vectors), dir(vectors), tnear(shape), tfar(shape);
  float *o = org.mutable_data(), *d = dir.mutable_data(), *tn = tnear.mutable_data(), *tf = tfar.mutable_data();
  for (size_t i = 0; i < rays.size(); ++i) {
    for (int a = 0; a < 3; ++a) {
      o[3 * i + size_t(a)] = rays[i].org[a];
      d[3 * i + size_t(a)] = rays[i].dir[a];
    }
    tn[i] = rays[i].tnear;
    tf[i] = rays[i].tfar;
  }
  return py::dict("origins"_a = org, "directions"_a = dir, "tnear"_a = tnear, "tfar"_a = tfar);
}

/// primary_rays(scene, width, height, order): the renderer's primary rays (analysis/raygen.h),
/// which come in its order (16x16 tiles of 4x2 packets): put in image order by their pixel
/// numbers, as (height, width) rays, or with order "tiles" left in it, flat, with those numbers.
py::dict camera_rays(const SceneHandle& s, int width, int height, const std::string& order) {
  RP_CHECK(order == "image" || order == "tiles", "order: '", order, "' is not image or tiles");
  RaySet set;
  {
    const auto lock = reading(s);
    set = primary_rays(*s.scene, width, height);
  }
  if (order == "tiles") {
    py::dict rays = ray_dict(set.rays);
    rays["pixel"] = py::array_t<uint32_t>(py::ssize_t(set.pixel.size()), set.pixel.data());
    return rays;
  }
  std::vector<Ray> image(set.rays.size());
  for (size_t k = 0; k < set.rays.size(); ++k) image[set.pixel[k]] = set.rays[k];
  return ray_dict(image, {py::ssize_t(height), py::ssize_t(width)});
}

/// pinhole_rays: the renderer's pinhole camera (render/camera.h) through every pixel centre of
/// a width x height image, as an (height, width, 6) float32 array of origin and direction in
/// image order (row 0 at the top).
py::array_t<float> pinhole_rays(int width, int height, const std::array<float, 3>& eye,
                                const std::array<float, 3>& look_at, const std::array<float, 3>& up, float fov) {
  const auto vec = [](const std::array<float, 3>& a) { return Vec3f(a[0], a[1], a[2]); };
  const Camera camera(
      CameraDesc{
          .eye = vec(eye), .look_at = vec(look_at), .up = vec(up), .vfov_degrees = fov, .model = CameraModel::pinhole},
      width, height);
  py::array_t<float> out({py::ssize_t(height), py::ssize_t(width), py::ssize_t(6)});
  float* const o = out.mutable_data();
  const size_t w = size_t(width);
  py::gil_scoped_release release;
  for_each_chunk(size_t(width) * size_t(height), [&](size_t begin, size_t n) {
    std::vector<float> px(n), py(n);
    std::vector<Ray> rays(n);
    for (size_t k = 0; k < n; ++k) {
      px[k] = float((begin + k) % w) + 0.5f;
      py[k] = float((begin + k) / w) + 0.5f;
    }
    camera.generate_rays(px, py, nullptr, rays);
    for (size_t k = 0; k < n; ++k)
      for (int a = 0; a < 3; ++a) {
        o[6 * (begin + k) + size_t(a)] = rays[k].org[a];
        o[6 * (begin + k) + 3 + size_t(a)] = rays[k].dir[a];
      }
  });
  return out;
}

py::dict hit_dict(std::span<const HitRecord> records) {
  HitArrays hits({py::ssize_t(records.size())}, true, false);
  float *t = hits.t.mutable_data(), *u = hits.u.mutable_data(), *v = hits.v.mutable_data();
  float* ng = hits.ng.mutable_data();
  uint32_t *prim = hits.prim_id.mutable_data(), *inst = hits.instance_id.mutable_data();
  for (size_t i = 0; i < records.size(); ++i) {
    t[i] = records[i].t;
    prim[i] = records[i].prim_id;
    inst[i] = records[i].instance_id;
    u[i] = records[i].u;
    v[i] = records[i].v;
    for (int a = 0; a < 3; ++a) ng[3 * i + size_t(a)] = records[i].ng[a];
  }
  return hits.to_dict();
}

void save_rays(const std::filesystem::path& path, const py::handle& origins, const py::handle& directions,
               const py::handle& tnear, const py::handle& tfar) {
  const RayArrays rays(origins, directions, tnear, tfar);
  py::gil_scoped_release release;
  size_t invalid = 0;  // a ray file may hold any ray: the tracer decides what is valid
  write_rays(path.string(), rays.records(invalid));
}

/// _gather_rays: the rays and masks RayArrays reads from a call's arguments, flat, and the
/// leading shape: what intersect, occluded and the queries trace, for the tests of the shapes.
py::dict gathered_rays(const py::handle& origins, const py::handle& directions, const py::handle& tnear,
                       const py::handle& tfar, const py::handle& mask) {
  const RayArrays rays(origins, directions, tnear, tfar, mask);
  size_t invalid = 0;
  const std::vector<Ray> records = rays.records(invalid);
  py::array_t<uint32_t> masks(py::ssize_t(rays.size()));
  rays.gather_masks(0, std::span(masks.mutable_data(), rays.size()));
  py::dict d = ray_dict(records);
  d["mask"] = masks;
  d["shape"] = py::tuple(py::cast(rays.shape()));
  d["has_mask"] = rays.has_mask();
  return d;
}

/// A backend given as a name (with its variant) or as a raypack.Backend already built, which
/// must have been built over `scene`.
using BackendArg = std::variant<std::string, const BackendHandle*>;

/// Backend.update(): brings the backend up to date with its scene (Backend::update), as a dict.
py::dict update(BackendHandle& b) {
  UpdateReport r;
  {
    py::gil_scoped_release release;
    const std::unique_lock writing(*b.scene.guard);
    r = b.backend->update();
  }
  return py::dict("seconds"_a = r.seconds, "refits"_a = r.refits, "rebuilds"_a = r.rebuilds, "top"_a = r.top);
}

/// The backend of `arg` over `scene`: the one given, or one built now (kept in `built`).
const Backend& backend_of(const BackendArg& arg, const std::string& variant, const SceneHandle& scene,
                          const char* what, std::optional<BackendHandle>& built) {
  if (const auto* given = std::get_if<const BackendHandle*>(&arg)) {
    RP_CHECK(*given != nullptr, what, ": None is not a backend name or a Backend");
    RP_CHECK((*given)->scene.scene == scene.scene, what, ": the backend was built over another scene (",
             (*given)->scene.name, ", not ", scene.name, ")");
    return *(*given)->backend;
  }
  built = build(std::get<std::string>(arg), scene, variant, "", "", BackendOptions{}.refit_limit);
  return *built->backend;
}

/// `values` as a numpy array of shape `shape` (whose product is values.size()) that takes over
/// their buffer: nothing is copied.
template <typename T>
py::array_t<T> owned_array(std::vector<T> values, std::vector<py::ssize_t> shape) {
  auto owned = std::make_unique<std::vector<T>>(std::move(values));
  T* const data = owned->data();
  const py::capsule owner(owned.release(), [](void* p) { delete static_cast<std::vector<T>*>(p); });
  return py::array_t<T>(std::move(shape), data, owner);
}

/// An image as the (height, width, 3) float32 array render returns; its buffer becomes the array's.
py::array_t<float> image_array(Image image) {
  return owned_array(std::move(image.rgb), {py::ssize_t(image.height), py::ssize_t(image.width), py::ssize_t(3)});
}

/// The geometry of each primitive of `prim_ids` (Scene::geometry_of; kInvalidId for kInvalidId).
std::vector<uint32_t> geometries_of(const Scene& scene, std::span<const uint32_t> prim_ids) {
  std::vector<uint32_t> out(prim_ids.size());
  for (size_t i = 0; i < prim_ids.size(); ++i)
    out[i] = prim_ids[i] == kInvalidId ? kInvalidId : scene.geometry_of(prim_ids[i]);
  return out;
}

/// render(..., aovs=True): the image and the primary hit through each pixel centre
/// (render_aovs, render/render.h) with the geometry of its primitive, each (height, width, ...)
/// in image order.
py::dict aov_dict(Image image, Aovs a, std::vector<uint32_t> geometry) {
  const py::ssize_t h = a.height, w = a.width;
  return py::dict("rgb"_a = image_array(std::move(image)), "depth"_a = owned_array(std::move(a.depth), {h, w}),
                  "normal"_a = owned_array(std::move(a.normal), {h, w, 3}),
                  "shading_normal"_a = owned_array(std::move(a.shading_normal), {h, w, 3}),
                  "uv"_a = owned_array(std::move(a.uv), {h, w, 2}),
                  "prim_id"_a = owned_array(std::move(a.prim_id), {h, w}),
                  "instance_id"_a = owned_array(std::move(a.instance_id), {h, w}),
                  "geometry_id"_a = owned_array(std::move(geometry), {h, w}));
}

py::object render_image(const SceneHandle& scene, const BackendArg& backend, const std::string& variant, int width,
                        int height, int spp, const std::string& sampler, uint64_t seed, int max_depth,
                        std::optional<std::array<float, 3>> eye, std::optional<std::array<float, 3>> look_at,
                        std::optional<std::array<float, 3>> up, std::optional<float> fov, bool aovs, int threads) {
  RenderSettings settings{.width = width, .height = height, .spp = spp, .sampler = Sampler::stratified, .seed = seed,
                          .max_depth = max_depth, .adaptive_threshold = 0.05f, .adaptive_depth = 3};
  if (sampler == "uniform") settings.sampler = Sampler::uniform;
  else if (sampler == "random") settings.sampler = Sampler::random;
  else if (sampler == "adaptive") settings.sampler = Sampler::adaptive;
  else RP_CHECK(sampler == "stratified", "sampler: '", sampler, "' is not uniform, random, stratified or adaptive");
  check_image_size("resolution", width, height);
  RP_CHECK(spp >= 1 && spp <= kMaxSpp, "spp: ", spp, " is out of range (1..", kMaxSpp, ")");
  RP_CHECK(max_depth >= 0 && max_depth <= 64, "max_depth: ", max_depth, " is out of range (0..64)");
  CameraDesc desc = [&] {
    const auto lock = reading(scene);
    return scene.scene->camera().value_or(frame_bounds(scene.scene->bounds(), scene.scene->up_axis()));
  }();
  const auto vec = [](const std::array<float, 3>& a) { return Vec3f(a[0], a[1], a[2]); };
  if (eye) desc.eye = vec(*eye);
  if (look_at) desc.look_at = vec(*look_at);
  if (up) desc.up = vec(*up);
  if (fov) desc.vfov_degrees = *fov;
  const Camera camera(desc, width, height);
  std::optional<BackendHandle> built;
  const Backend& b = backend_of(backend, variant, scene, "render", built);
  Image image;
  Aovs primary;
  std::vector<uint32_t> geometry;
  // Ctrl-C stops the render between tiles (python/interrupt.h).
  interruptible(true, [&](const std::atomic<bool>& stop) {
    const ProgressFn stop_between_tiles = [&](double) {
      if (stop.load(std::memory_order_relaxed)) throw Stopped();
    };
    const auto lock = reading(scene);
    with_threads(threads, [&] {
      image = render(*scene.scene, b, camera, settings, stop_between_tiles).image;
      if (!aovs) return;
      primary = render_aovs(*scene.scene, b, camera);
      geometry = geometries_of(*scene.scene, primary.prim_id);
    });
  });
  if (!aovs) return image_array(std::move(image));
  return aov_dict(std::move(image), std::move(primary), std::move(geometry));
}

void save_image(const std::filesystem::path& path, const py::handle& pixels) {
  const auto a = numbers<float, py::array::c_style | py::array::forcecast>("image", pixels);
  if (a.ndim() != 3 || a.shape(2) != 3) throw Error(cat("image: shape ", shape_text(a), " is not (height, width, 3)"));
  check_image_size(cat("image: shape ", shape_text(a)), a.shape(1), a.shape(0));
  Image image{.width = int(a.shape(1)), .height = int(a.shape(0)), .rgb = {a.data(), a.data() + a.size()}};
  py::gil_scoped_release release;
  write_image(path.string(), image);
}

py::object diff(const SceneHandle& scene, const py::handle& origins, const py::handle& directions,
                const py::handle& tnear, const py::handle& tfar, const BackendArg& a, const BackendArg& b,
                const std::string& variant_a, const std::string& variant_b, bool coherent, bool reference,
                double tie_tolerance, double t_tolerance, const std::string& rays_label, int threads) {
  RP_CHECK(tie_tolerance >= 0 && tie_tolerance <= 1, "tie_tolerance: ", tie_tolerance, " is outside [0, 1]");
  RP_CHECK(t_tolerance >= 0 && t_tolerance <= 1, "t_tolerance: ", t_tolerance, " is outside [0, 1]");
  const RayArrays rays(origins, directions, tnear, tfar);
  const auto is_reference = [](const BackendArg& s) {
    const auto* name = std::get_if<std::string>(&s);
    return name && *name == "reference";
  };
  // The sides' labels as `raypack diff` writes them: backend/variant, or reference.
  const auto label = [&](const BackendArg& s, const std::string& variant) -> std::string {
    if (is_reference(s)) return "reference";
    if (const auto* given = std::get_if<const BackendHandle*>(&s))
      return (*given)->backend->info().name + "/" + (*given)->backend->info().variant;
    return std::get<std::string>(s) + "/" + variant;
  };
  std::optional<BackendHandle> built_a, built_b;
  const Backend* backend_a = is_reference(a) ? nullptr : &backend_of(a, variant_a, scene, "a", built_a);
  const Backend* backend_b = is_reference(b) ? nullptr : &backend_of(b, variant_b, scene, "b", built_b);
  const DiffOptions options{tie_tolerance, t_tolerance};
  std::string json;
  {
    py::gil_scoped_release release;
    const auto lock = reading(scene);
    with_threads(threads, [&] {
      size_t invalid = 0;  // diffed as every side traces them: misses
      const std::vector<Ray> records = rays.records(invalid);
      std::vector<ReferenceHit> ref;
      if (reference || !backend_a || !backend_b) {
        ref.resize(records.size());
        Reference(*scene.scene).intersect(records, ref);
      }
      const auto hits = [&](const Backend* backend) {
        std::vector<Hit> h(records.size());
        if (backend) {
          intersect_parallel(*backend, records, h, coherent ? Coherence::coherent : Coherence::incoherent);
        } else {
          for (size_t i = 0; i < ref.size(); ++i) h[i] = to_hit(ref[i]);
        }
        return h;
      };
      const std::vector<Hit> hits_a = hits(backend_a), hits_b = hits(backend_b);
      const DiffResult d = diff_hits(*scene.scene, records, hits_a, hits_b,
                                     reference ? std::span<const ReferenceHit>(ref) : std::span<const ReferenceHit>(),
                                     options);
      json = to_json(d, scene.name, rays_label, label(a, variant_a), label(b, variant_b), options);
    });
  }
  return py::module_::import("json").attr("loads")(json);
}

py::list backend_list() {
  py::list out;
  for (const BackendEntry& e : list_backends()) {
    py::dict facts;
    for (const auto& [k, v] : e.facts) facts[py::str(k)] = v;
    out.append(py::dict("name"_a = e.name, "description"_a = e.description, "variants"_a = e.variants,
                        "coherent_methods"_a = e.coherent_methods, "incoherent_methods"_a = e.incoherent_methods,
                        "facts"_a = facts, "available"_a = e.available, "unavailable_reason"_a = e.unavailable_reason));
  }
  return out;
}

}  // namespace
}  // namespace rp::python

PYBIND11_MODULE(_raypack, m) {
  using namespace rp;
  using namespace rp::python;
  namespace py = pybind11;
  m.doc() = "raypack: ray casting over numpy arrays through the simd and embree backends (see README.md)";
  m.attr("__version__") = RAYPACK_VERSION;
  py::register_exception<Error>(m, "Error", PyExc_ValueError);

  define_scene(m);

  py::class_<BackendHandle>(m, "Backend",
                            "A backend built over a scene, safe to call from many threads at once.\n"
                            "It keeps its scene alive for as long as it lives. When the scene changes, tracing\n"
                            "raises raypack.Error until update() brings the backend up to date.")
      .def(py::init(&build), "name"_a, "scene"_a, "variant"_a = "default", py::kw_only(), "coherent_method"_a = "",
           "incoherent_method"_a = "", "refit_limit"_a = BackendOptions{}.refit_limit,
           "Builds backend `name` (see backends()) over `scene`; raises raypack.Error for an unknown or\n"
           "unavailable backend or variant, with the message of `raypack --backend`. refit_limit (simd):\n"
           "update() rebuilds a tree whose SAH cost after a refit passes this multiple of its built cost.")
      .def("update", &update,
           "Brings the backend up to date with its scene's changes, with the least work: moved vertices\n"
           "refit their trees, moved instances rebuild the instance level, added geometry is built.\n"
           "Returns a dict: seconds, refits and rebuilds (trees), top (the instance level rebuilt).")
      .def_property_readonly(
          "current",
          [](const BackendHandle& b) {
            const auto lock = reading(b.scene);
            return b.backend->current();
          },
          "True when no change of the scene awaits update()")
      .def("intersect", &intersect, "origins"_a, "directions"_a = py::none(), "tnear"_a = 0.0f, tfar_arg(),
           "coherent"_a = false, py::kw_only(), "mask"_a = py::none(), "invalid"_a = "warn", "normals"_a = true,
           "threads"_a = 0,
           "Closest hits: a dict of numpy arrays t, prim_id (uint32, 0xffffffff on a miss), u, v, instance_id\n"
           "(uint32, 0xffffffff on a miss or outside any instance), geometry_id (uint32, 0xffffffff on a miss)\n"
           "and ng (..., 3), the unit geometric normal (left out with normals=False, which saves working it\n"
           "out), each of the rays' leading shape (...).\n"
           "Rays: origins and directions (..., 3), such as (N, 3) or (H, W, 3), a (3,) one shared by every ray;\n"
           "or one array (..., 6) of origin and direction (Open3D's layout) with directions left out.\n"
           "tnear, tfar: scalars or arrays of the leading shape; all broadcast by numpy's rule.\n"
           "mask: uint32 per ray (or one for all): a ray sees a geometry when mask & Scene.mask(geometry) != 0.\n"
           "float32 input is read in place. Rays outside the valid-ray rule are misses;\n"
           "invalid='warn' (RuntimeWarning), 'raise' or 'miss'. threads: 0 uses every core.\n"
           "The GIL is released while tracing.")
      .def("occluded", &occluded, "origins"_a, "directions"_a = py::none(), "tnear"_a = 0.0f, tfar_arg(),
           "coherent"_a = false, py::kw_only(), "mask"_a = py::none(), "invalid"_a = "warn", "threads"_a = 0,
           "Any hit within [tnear, tfar]: a bool array of the rays' leading shape, True where the ray is\n"
           "occluded. Arguments as intersect.")
      .def_property_readonly("name", [](const BackendHandle& b) { return b.backend->info().name; })
      .def_property_readonly("variant", [](const BackendHandle& b) { return b.backend->info().variant; })
      .def_property_readonly("scene", [](const BackendHandle& b) { return b.scene; })
      .def_property_readonly("build_seconds", [](const BackendHandle& b) { return b.backend->info().build_seconds; })
      .def_property_readonly(
          "bytes", [](const BackendHandle& b) { return b.backend->info().bytes; },
          "Bytes of the acceleration structure")
      .def_property_readonly("stats",
                             [](const BackendHandle& b) {
                               py::dict d;
                               for (const auto& [k, v] : b.backend->info().stats) d[py::str(k)] = v;
                               return d;
                             })
      .def("__repr__", [](const BackendHandle& b) {
        return cat("<raypack.Backend ", b.backend->info().name, "/", b.backend->info().variant, " over '",
                   b.scene.name, "'>");
      });

  m.def("backends", &backend_list,
        "Every backend: name, description, variants, coherent and incoherent methods, facts, and whether\n"
        "this machine runs it (available, unavailable_reason).");
  m.def("render", &render_image, "scene"_a, "backend"_a = std::string(kDefaultBackend), "variant"_a = "default",
        py::kw_only(), "width"_a = 1024, "height"_a = 768, "spp"_a = 1, "sampler"_a = "stratified", "seed"_a = 0,
        "max_depth"_a = 3, "eye"_a = py::none(), "look_at"_a = py::none(), "up"_a = py::none(), "fov"_a = py::none(),
        "aovs"_a = false, "threads"_a = 0,
        "Renders as `raypack render` does: an (height, width, 3) float32 array of linear RGB, top row first.\n"
        "backend: a name or a Backend built over `scene`; the camera is the scene's (or one framing it),\n"
        "with eye, look_at, up (x, y, z) and fov (vertical, degrees) replacing its own when given.\n"
        "aovs=True: a dict of that image (rgb) and the primary hit through each pixel centre, as\n"
        "`raypack render --aov` writes them: depth (H, W; distance, inf on a miss), normal and\n"
        "shading_normal (H, W, 3; world, unit, facing the camera, 0 on a miss), uv (H, W, 2),\n"
        "prim_id and instance_id (H, W; uint32, 0xffffffff on a miss).");
  m.def("diff", &diff, "scene"_a, "origins"_a, "directions"_a, "tnear"_a = 0.0f, tfar_arg(), py::kw_only(),
        "a"_a = std::string(kDefaultBackend), "b"_a = "simd", "variant_a"_a = "default", "variant_b"_a = "default",
        "coherent"_a = false, "reference"_a = true, "tie_tolerance"_a = 1e-6, "t_tolerance"_a = 1e-4,
        "rays_label"_a = "numpy", "threads"_a = 0,
        "The same rays through sides a and b (backend names, Backends, or 'reference') and the double-\n"
        "precision reference: the summary `raypack diff --json` writes, as a dict.");
  m.def("primary_rays", &camera_rays, "scene"_a, "width"_a, "height"_a, py::kw_only(), "order"_a = "image",
        "The rays of the scene's camera (or one framing it) through every pixel centre, as the\n"
        "renderer makes them, in image order (row 0 at the top): a dict of origins and directions\n"
        "(height, width, 3), tnear and tfar (height, width), so hits come as images.\n"
        "order='tiles': flat, (N, 3) and (N,), in the renderer's order (16x16-pixel tiles of 4x2-pixel\n"
        "packets, as `raypack diff --kind primary` traces them), with pixel (N,), uint32: each ray's\n"
        "pixel, y * width + x (take it out before intersect(**rays)).");
  m.def("pinhole_rays", &pinhole_rays, "width"_a, "height"_a, "eye"_a, "look_at"_a, "up"_a, "fov"_a,
        "The renderer's pinhole camera at eye, looking at look_at, with up and a vertical field of view\n"
        "fov (degrees): one ray through every pixel centre, an (height, width, 6) float32 array of\n"
        "origin and direction (unit) in image order (row 0 at the top), which intersect takes as it is.");
  m.def(
      "random_rays",
      [](const SceneHandle& s, size_t count, uint64_t seed) {
        const auto lock = reading(s);
        return ray_dict(random_rays(*s.scene, count, seed).rays);
      },
      "scene"_a, "count"_a, "seed"_a = 1,
      "`count` seeded rays from the sphere around the scene into its bounds (incoherent): a dict of\n"
      "origins and directions (count, 3), tnear and tfar (count,).");
  m.def("_gather_rays", &gathered_rays, "origins"_a, "directions"_a = py::none(), "tnear"_a = 0.0f, tfar_arg(),
        "mask"_a = py::none(),
        "For the tests: the rays intersect would trace for these arguments, flat (a dict as read_rays\n"
        "returns, with each ray's mask), and their leading shape.");
  m.def("write_rays", &save_rays, "path"_a, "origins"_a, "directions"_a, "tnear"_a = 0.0f, tfar_arg(),
        "Writes a ray file (.csv, or binary: .bin, .rays) that `raypack trace --rays` reads.");
  m.def("read_rays", [](const std::filesystem::path& path) { return ray_dict(read_rays(path.string())); }, "path"_a,
        "Reads a ray file, as the dict primary_rays returns.");
  m.def("write_image", &save_image, "path"_a, "image"_a,
        "Writes an (height, width, 3) array of linear RGB as `raypack render -o` does: the format by the\n"
        "extension, 8-bit formats (.png, .jpg) with the sRGB curve, .exr as float.");
  m.def("read_image", [](const std::filesystem::path& path) { return image_array(read_image(path.string())); }, "path"_a,
        "Reads an image file as an (height, width, 3) float32 array, as stored (EXR: linear).");
  m.def("read_hits", [](const std::filesystem::path& path) { return hit_dict(read_hits(path.string())); }, "path"_a,
        "Reads a hit file (`raypack trace -o`), as the dict Backend.intersect returns.");

  define_queries(m);
  add_text_signatures(m);
}
