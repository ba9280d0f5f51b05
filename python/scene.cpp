#include "python/scene.h"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <type_traits>
#include <utility>

#include "base/error.h"
#include "io/loaders/load.h"
#include "python/handles.h"
#include "python/ray_arrays.h"

namespace rp::python {
namespace {

using namespace pybind11::literals;

SceneHandle load(const std::filesystem::path& path) {
  const std::string name = path.string();
  py::gil_scoped_release release;
  return {std::make_shared<Scene>(load_scene(name)), name};
}

/// A C-order (rows, columns) array of `what` as T (converted when it is another dtype: the scene
/// copies it anyway). Throws rp::Error for another shape, naming `shape`, the one expected.
template <typename T>
py::array_t<T, py::array::c_style | py::array::forcecast> table(const char* what, const py::handle& object,
                                                                py::ssize_t columns, const char* shape) {
  auto a = numbers<T, py::array::c_style | py::array::forcecast>(what, object);
  if (a.ndim() != 2 || a.shape(1) != columns) throw Error(cat(what, ": shape ", shape_text(a), " is not ", shape));
  return a;
}

/// A triangle mesh named `name` from Python arrays: positions (V, 3) of `vertices` and vertex
/// numbers (T, 3) of `triangles`, which must be integers: a float array would be truncated (2.9
/// read as 2) and a uint64 one wrap to negative numbers, so both are refused, naming the
/// argument as `triangles_arg`, and the values are checked.
TriangleMesh mesh_of(std::string name, const py::handle& vertices, const char* triangles_arg,
                     const py::handle& triangles) {
  const auto positions = table<float>("vertices", vertices, 3, "(V, 3)");  // held while v reads it
  const auto v = positions.unchecked<2>();
  const py::array given = py::array::ensure(triangles);
  const char kind = given ? given.dtype().kind() : '?';
  RP_CHECK(kind == 'i' || kind == 'u', triangles_arg, ": ",
           given ? cat("dtype ", std::string(py::str(given.dtype()))) : std::string("this"),
           " is not an array of integers (vertex numbers)");
  TriangleMesh mesh;
  mesh.name = std::move(name);
  mesh.positions.resize(size_t(v.shape(0)));
  for (py::ssize_t i = 0; i < v.shape(0); ++i) mesh.positions[size_t(i)] = {v(i, 0), v(i, 1), v(i, 2)};
  const auto take = [&](const auto& idx) {
    mesh.indices.resize(size_t(idx.size()));
    const auto* in = idx.data();
    for (size_t i = 0; i < mesh.indices.size(); ++i) {
      bool negative = false;
      if constexpr (std::is_signed_v<std::remove_cvref_t<decltype(in[i])>>) negative = in[i] < 0;
      RP_CHECK(!negative && uint64_t(in[i]) < kInvalidId, triangles_arg, ": ", in[i], " (triangle ", i / 3,
               ") is not a vertex index");
      mesh.indices[i] = uint32_t(in[i]);
    }
  };
  if (kind == 'u')
    take(table<uint64_t>(triangles_arg, given, 3, "(T, 3)"));
  else
    take(table<int64_t>(triangles_arg, given, 3, "(T, 3)"));
  return mesh;
}

SceneHandle from_arrays(const py::handle& vertices, const py::handle& indices, const py::handle& spheres,
                        const py::handle& planes) {
  TriangleMesh mesh = mesh_of("arrays", vertices, "indices", indices);
  Scene scene;
  scene.add_mesh(std::move(mesh));
  if (!spheres.is_none()) {
    const auto array = table<float>("spheres", spheres, 4, "(S, 4): centre x, y, z and radius");
    const auto s = array.unchecked<2>();
    for (py::ssize_t i = 0; i < s.shape(0); ++i)
      scene.add_sphere(Sphere{.center = {s(i, 0), s(i, 1), s(i, 2)}, .radius = s(i, 3), .material = 0});
  }
  if (!planes.is_none()) {
    const auto array = table<float>("planes", planes, 4, "(P, 4): normal x, y, z and d of n.P + d = 0");
    const auto p = array.unchecked<2>();
    for (py::ssize_t i = 0; i < p.shape(0); ++i)
      scene.add_plane(Plane{.normal = {p(i, 0), p(i, 1), p(i, 2)}, .d = p(i, 3), .material = 0});
  }
  return {std::make_shared<Scene>(std::move(scene)), "arrays"};
}

/// A (3,) vector of `what`. Throws rp::Error naming it for another shape.
Vec3f vec3_of(const char* what, const py::handle& object) {
  const auto a = numbers<float, py::array::c_style | py::array::forcecast>(what, object);
  RP_CHECK(a.ndim() == 1 && a.shape(0) == 3, what, ": shape ", shape_text(a), " is not (3,)");
  return {a.data()[0], a.data()[1], a.data()[2]};
}

/// `object` as a numpy array of `rows` x 3 items of 4 bytes of `kinds` (dtype kinds), each row's
/// three items adjacent and rows any multiple of 4 bytes apart (a C-order (N, 3) array, or
/// the first three columns of a wider one): what the scene can view in place. Throws
/// rp::Error naming `what` and what is wrong.
py::array in_place(const char* what, const py::handle& object, const char* kinds, const char* dtypes) {
  RP_CHECK(py::isinstance<py::array>(object), what, ": copy=False needs a numpy array, not ",
           std::string(py::str(py::type::handle_of(object).attr("__name__"))));
  py::array a = py::reinterpret_borrow<py::array>(object);
  const char kind = a.dtype().kind();
  RP_CHECK(std::string(kinds).find(kind) != std::string::npos && a.itemsize() == 4, what, ": copy=False needs ", dtypes,
           ", not ", std::string(py::str(a.dtype())));
  RP_CHECK(a.ndim() == 2 && a.shape(1) == 3, what, ": shape ", shape_text(a), " is not (N, 3)");
  RP_CHECK(a.strides(1) == 4 && a.strides(0) >= 12 && a.strides(0) % 4 == 0, what, ": copy=False needs each row's 3 ",
           "values adjacent and rows a multiple of 4 bytes apart; strides (", a.strides(0), ", ", a.strides(1),
           ") are not (use copy=True, or np.ascontiguousarray)");
  return a;
}

/// Scene.add_triangles(vertices, triangles, copy): a new world mesh; its geometry id. With
/// copy=False the scene views the arrays in place (Scene::add_shared_mesh) and keeps them.
uint32_t add_triangles(const SceneHandle& s, const py::handle& vertices, const py::handle& triangles, bool copy) {
  if (copy) {
    TriangleMesh mesh = mesh_of("arrays", vertices, "triangles", triangles);
    return changing(s, [&](Scene& scene) { return scene.mesh_geometry(scene.add_mesh(std::move(mesh))); });
  }
  const py::array v = in_place("vertices", vertices, "f", "float32");
  const py::array t = in_place("triangles", triangles, "iu", "int32 or uint32");
  MeshView mesh;
  mesh.name = "arrays";
  mesh.positions = {static_cast<const Vec3f*>(v.data()), size_t(v.shape(0)), size_t(v.strides(0))};
  mesh.triangles = {static_cast<const TriangleIndices*>(t.data()), size_t(t.shape(0)), size_t(t.strides(0))};
  const uint32_t g = changing(s, [&](Scene& scene) { return scene.mesh_geometry(scene.add_shared_mesh(mesh)); });
  s.kept->arrays.push_back(v);
  s.kept->arrays.push_back(t);
  return g;
}

uint32_t add_sphere(const SceneHandle& s, const py::handle& center, float radius) {
  const Sphere sphere{.center = vec3_of("center", center), .radius = radius, .material = 0};
  return changing(s, [&](Scene& scene) { return scene.add_sphere(sphere); });
}

uint32_t add_plane(const SceneHandle& s, const py::handle& normal, float d) {
  const Plane plane{.normal = vec3_of("normal", normal), .d = d, .material = 0};
  return changing(s, [&](Scene& scene) { return scene.add_plane(plane); });
}

uint32_t add_polygon(const SceneHandle& s, const py::handle& vertices) {
  const auto array = table<float>("vertices", vertices, 3, "(K, 3)");
  const std::span<const Vec3f> corners(reinterpret_cast<const Vec3f*>(array.data()), size_t(array.shape(0)));
  return changing(s, [&](Scene& scene) { return scene.add_polygon(corners, 0); });
}

/// Scene.add_quadric(coefficients, clip_min, clip_max, *, center): A..J of
/// A x^2 + B y^2 + C z^2 + D xy + E yz + F xz + G x + H y + I z + J = 0 about `center`, clipped
/// to the box.
uint32_t add_quadric(const SceneHandle& s, const py::handle& coefficients, const py::handle& clip_min,
                     const py::handle& clip_max, const py::handle& center) {
  const auto c = numbers<float, py::array::c_style | py::array::forcecast>("coefficients", coefficients);
  RP_CHECK(c.ndim() == 1 && c.shape(0) == 10, "coefficients: shape ", shape_text(c), " is not (10,): A .. J");
  const float* k = c.data();
  QuadricShape q;
  q.quadric = Quadricf{.A = k[0],
                       .B = k[1],
                       .C = k[2],
                       .D = k[3],
                       .E = k[4],
                       .F = k[5],
                       .G = k[6],
                       .H = k[7],
                       .I = k[8],
                       .J = k[9],
                       .center = vec3_of("center", center),
                       .clip = Box3f(vec3_of("clip_min", clip_min), vec3_of("clip_max", clip_max))};
  return changing(s, [&](Scene& scene) { return scene.add_quadric(q); });
}

/// Scene.mask(geometry), checked against the geometry count.
uint32_t geometry_mask(const SceneHandle& s, uint32_t geometry) {
  const auto lock = reading(s);
  RP_CHECK(geometry < s.scene->geometry_count(), "mask: geometry ", geometry, " out of range (",
           s.scene->geometry_count(), " geometries)");
  return s.scene->mask(geometry);
}

/// Scene.vertices(mesh): a copy of mesh `mesh`'s positions, (V, 3) float32.
py::array_t<float> vertices(const SceneHandle& s, uint32_t mesh) {
  const auto lock = reading(s);
  RP_CHECK(mesh < s.scene->meshes().size(), "mesh ", mesh, " out of range (", s.scene->meshes().size(), " meshes)");
  const Strided<Vec3f>& p = s.scene->meshes()[mesh].positions;
  py::array_t<float> out({py::ssize_t(p.size()), py::ssize_t(3)});
  std::copy(p.begin(), p.end(), reinterpret_cast<Vec3f*>(out.mutable_data()));
  return out;
}

/// Scene.set_vertices(mesh, vertices): new positions for mesh `mesh` (Scene::set_vertices).
void set_vertices(const SceneHandle& s, uint32_t mesh, const py::handle& vertices) {
  const auto array = table<float>("vertices", vertices, 3, "(V, 3)");
  const std::span<const Vec3f> p(reinterpret_cast<const Vec3f*>(array.data()), size_t(array.shape(0)));
  changing(s, [&](Scene& scene) { scene.set_vertices(mesh, p); });
}

/// Scene.transform(instance): instance `instance`'s object-to-world map as a (4, 4) float32 matrix.
py::array_t<float> transform(const SceneHandle& s, uint32_t instance) {
  const auto lock = reading(s);
  RP_CHECK(instance < s.scene->instances().size(), "instance ", instance, " out of range (",
           s.scene->instances().size(), " instances)");
  const Affine3f& m = s.scene->instances()[instance].object_to_world;
  py::array_t<float> out({py::ssize_t(4), py::ssize_t(4)});
  float* o = out.mutable_data();
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) o[4 * i + j] = i < 3 ? m.m[i][j] : float(j == 3);
  return out;
}

/// Scene.set_transform(instance, matrix): a (4, 4) matrix whose last row is 0 0 0 1, or its
/// top (3, 4) rows (Scene::set_transform).
void set_transform(const SceneHandle& s, uint32_t instance, const py::handle& matrix) {
  const auto a = numbers<float, py::array::c_style | py::array::forcecast>("matrix", matrix);
  RP_CHECK(a.ndim() == 2 && (a.shape(0) == 3 || a.shape(0) == 4) && a.shape(1) == 4, "matrix: shape ", shape_text(a),
           " is not (4, 4) or (3, 4)");
  const float* m = a.data();
  RP_CHECK(a.shape(0) == 3 || (m[12] == 0.0f && m[13] == 0.0f && m[14] == 0.0f && m[15] == 1.0f),
           "matrix: its last row (", m[12], ", ", m[13], ", ", m[14], ", ", m[15], ") is not 0 0 0 1: not affine");
  Affine3f t;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 4; ++j) t.m[i][j] = m[4 * i + j];
  changing(s, [&](Scene& scene) { scene.set_transform(instance, t); });
}

}  // namespace

void define_scene(py::module_& m) {
  py::class_<SceneHandle>(m, "Scene",
                          "A scene: triangle meshes, instances, analytic primitives, materials, lights and a camera.\n"
                          "Made by load_scene(), Scene.from_arrays(), or Scene() and its add_* calls; it owns\n"
                          "copies of its data. Geometry may be added, its meshes' vertices and its instances'\n"
                          "transforms may change (set_vertices, set_transform); a Backend over it then raises\n"
                          "raypack.Error until its update().")
      .def(py::init([] {
             return SceneHandle{std::make_shared<Scene>(), "arrays"};
           }),
           "An empty scene, to fill with add_triangles, add_sphere, add_plane, add_polygon and add_quadric.")
      .def("add_triangles", &add_triangles, "vertices"_a, "triangles"_a, py::kw_only(), "copy"_a = true,
           "Adds a triangle mesh: vertices (V, 3) floats, triangles (T, 3) integers (vertex numbers).\n"
           "Returns its geometry id. Backends over the scene need update(). The data is copied, or with\n"
           "copy=False read in place: vertices float32 and triangles int32 or uint32, each row's 3 values\n"
           "adjacent (C order, or the first columns of a wider array); the scene keeps the arrays alive.\n"
           "After writing new vertices into them, call vertices_changed(mesh), then each Backend's update().")
      .def("add_sphere", &add_sphere, "center"_a, "radius"_a,
           "Adds a sphere (centre (3,), radius > 0); returns its geometry id.")
      .def("add_plane", &add_plane, "normal"_a, "d"_a,
           "Adds the unbounded plane n.P + d = 0 (normal (3,), not zero); returns its geometry id.")
      .def("add_polygon", &add_polygon, "vertices"_a,
           "Adds a planar polygon of K >= 3 coplanar vertices (K, 3), convex or not; returns its geometry id.")
      .def("add_quadric", &add_quadric, "coefficients"_a, "clip_min"_a, "clip_max"_a, py::kw_only(),
           "center"_a = py::make_tuple(0.0f, 0.0f, 0.0f),
           "Adds the quadric A x^2 + B y^2 + C z^2 + D xy + E yz + F xz + G x + H y + I z + J = 0, its\n"
           "coefficients (10,) A .. J written about `center`, clipped to the box clip_min .. clip_max\n"
           "(finite). Returns its geometry id.")
      .def_property_readonly(
          "geometry_count",
          [](const SceneHandle& s) {
            const auto lock = reading(s);
            return s.scene->geometry_count();
          },
          "Geometries: every mesh, sphere, quadric, polygon and plane, numbered 0, 1, ... in the order they were\n"
          "added (Scene.from_arrays: the mesh, then the spheres, then the planes); the geometry_id of hits")
      .def(
          "set_mask",
          [](const SceneHandle& s, uint32_t geometry, uint32_t mask) {
            changing(s, [&](Scene& scene) { scene.set_mask(geometry, mask); });
          },
          "geometry"_a, "mask"_a,
          "Sets a geometry's 32-bit mask (0xffffffff at first): a ray of mask m sees it only when\n"
          "m & mask != 0 (intersect's mask=; Embree's rule). Takes effect at once: no update() needed.")
      .def("mask", &geometry_mask, "geometry"_a, "A geometry's mask")
      .def_static("from_arrays", &from_arrays, "vertices"_a, "indices"_a, py::kw_only(), "spheres"_a = py::none(),
                  "planes"_a = py::none(),
                  "A scene of one triangle mesh: vertices (V, 3) floats, indices (T, 3) integers (vertex numbers);\n"
                  "optionally spheres (S, 4): centre and radius, and planes (P, 4): normal and d of n.P + d = 0.\n"
                  "prim_id numbers the triangles, then the spheres, then the planes. The data is copied.")
      .def_property_readonly(
          "name", [](const SceneHandle& s) { return s.name; }, "The path it was loaded from, 'default', or 'arrays'")
      .def_property_readonly("prim_count",
                             [](const SceneHandle& s) {
                               const auto lock = reading(s);
                               return s.scene->prim_count();
                             })
      .def_property_readonly("triangle_count",
                             [](const SceneHandle& s) {
                               const auto lock = reading(s);
                               return s.scene->triangle_count();
                             })
      .def_property_readonly("mesh_count",
                             [](const SceneHandle& s) {
                               const auto lock = reading(s);
                               return s.scene->meshes().size();
                             })
      .def_property_readonly("instance_count",
                             [](const SceneHandle& s) {
                               const auto lock = reading(s);
                               return s.scene->instances().size();
                             })
      .def_property_readonly(
          "version",
          [](const SceneHandle& s) {
            const auto lock = reading(s);
            return s.scene->version();
          },
          "Raised by every change of the geometry")
      .def("vertices", &vertices, "mesh"_a, "A copy of mesh `mesh`'s vertex positions, (V, 3) float32")
      .def("set_vertices", &set_vertices, "mesh"_a, "vertices"_a,
           "New positions (V, 3) for mesh `mesh`'s vertices, as many as it has (its triangles stay).\n"
           "Raises raypack.Error, changing nothing, for another count or a coordinate that is not finite\n"
           "or outside the supported range. Backends over the scene need update() before tracing again.")
      .def(
          "vertices_changed",
          [](const SceneHandle& s, uint32_t mesh) { changing(s, [&](Scene& scene) { scene.vertices_changed(mesh); }); },
          "mesh"_a,
          "Mesh `mesh` (added with copy=False) has new vertex positions, written into its array in place:\n"
          "checks them as set_vertices does (raypack.Error naming the vertex, the scene unchanged) and\n"
          "raises the version, so that Backends over the scene need update() before tracing again.")
      .def("transform", &transform, "instance"_a, "Instance `instance`'s object-to-world matrix, (4, 4) float32")
      .def("set_transform", &set_transform, "instance"_a, "matrix"_a,
           "A new object-to-world matrix, (4, 4) with last row 0 0 0 1 or (3, 4), for instance `instance`.\n"
           "Raises raypack.Error, changing nothing, for a matrix that is not finite or not invertible.\n"
           "Backends over the scene need update() before tracing again.")
      .def_property_readonly(
          "bounds",
          [](const SceneHandle& s) {
            const auto lock = reading(s);
            const Box3f b = s.scene->bounds();
            return std::pair{std::array<float, 3>{b.lo.x, b.lo.y, b.lo.z},
                             std::array<float, 3>{b.hi.x, b.hi.y, b.hi.z}};
          },
          "(lo, hi) corners of the bounded primitives' box (planes left out)")
      .def("__repr__", [](const SceneHandle& s) {
        const auto lock = reading(s);
        return cat("<raypack.Scene '", s.name, "': ", s.scene->prim_count(), " primitives, ", s.scene->triangle_count(),
                   " triangles>");
      });

  m.def("load_scene", &load, "path"_a,
        "Loads an .obj, .ply, .gltf, .glb or .json scene file, or the embedded scene for 'default'; raises "
        "raypack.Error\n"
        "naming the file and line of the first problem.");
}

}  // namespace rp::python
