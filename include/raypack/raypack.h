#pragma once
/// raypack's public C++ API: the one header a program includes (`#include <raypack/raypack.h>`)
/// after `find_package(raypack CONFIG REQUIRED)` and `target_link_libraries(x raypack::raypack)`,
/// or with `pkg-config --cflags --libs raypack`. C++20. Everything is in namespace rp.
///
/// What it offers, and the header that documents each part (installed beside this one):
/// - scenes: rp::load_scene(path) for .obj, .ply, .json, .gltf and .glb files or "default",
///   and rp::load_animated_scene(path) for the scene with its animation, which
///   SceneAnimation::apply poses at a time (io/loaders/load.h, io/loaders/animation.h);
///   rp::Scene built from arrays: Scene::add_mesh(TriangleMesh{
///   .positions, .indices}) (copied), Scene::add_shared_mesh(MeshView{.positions,
///   .triangles}) (the caller's strided buffers, not copied), add_sphere, add_quadric,
///   add_polygon, add_plane, lights, materials and a camera (core/scene.h);
/// - backends: rp::list_backends() (names, variants, coherent and incoherent methods, whether
///   this machine runs them), rp::check_method, rp::make_backend(name, scene, options)
///   (backends/registry.h);
/// - tracing: Backend::intersect (closest hit) and Backend::occluded (any hit) over spans of
///   rp::Ray with an rp::Coherence hint, rp::intersect_parallel / occluded_parallel over all
///   cores (core/backend.h); rays, hits, the valid-ray rule and the hit convention
///   (core/ray.h); ray and hit files (io/rayfile.h);
/// - queries (core/queries.h, docs/queries.md): masks and hit filters (rp::TraceOptions),
///   Backend::all_hits and count_hits along rays, Backend::closest_points, rp::inside and
///   rp::signed_distance; geometry ids and masks (Scene::geometry_of, Scene::set_mask);
/// - judging: the double-precision rp::Reference (analysis/reference.h), rp::diff_hits
///   and its summary as a table or as the JSON of `raypack diff --json`
///   (analysis/diff.h), ray sets (analysis/raygen.h);
/// - images: rp::render with a Camera (render/render.h, render/camera.h),
///   rp::write_image (render/image_io.h);
/// - versions: RAYPACK_VERSION_MAJOR, _MINOR, _PATCH and RAYPACK_VERSION_STRING, the headers'
///   version at compile time, and rp::version(), the library's at run time (raypack/version.h).
///
/// Hit convention: a hit counts only for tnear <= t <= tfar (both ends closed); directions
/// are never normalized (t is in units of the direction's length); a miss is Hit{}:
/// prim_id == rp::kInvalidId (0xffffffff), t == +inf, u == v == 0; prim_id numbers the
/// triangles of every mesh in order, then spheres, quadrics, polygons and planes; for
/// triangles p = (1-u-v) v0 + u v1 + v v2. A ray outside rp::valid_ray (NaN, infinite, beyond
/// the coordinate range, tnear > tfar) is a miss and never occluded, on every backend.
///
/// Ownership:
/// - a Scene owns all its data (add_* copy or move it in) but for shared meshes
///   (Scene::add_shared_mesh), whose buffers the caller keeps valid and unchanged, as for
///   Embree's shared buffers, while the scene, a copy of it or a backend over either is used,
///   and whose in-place changes it announces by Scene::vertices_changed; load_scene returns
///   a scene by value;
/// - a Backend reads the Scene it was built over for as long as it lives. Either the caller
///   keeps the scene alive until the backend is destroyed (make_backend(name, scene), scene an
///   lvalue; a temporary scene does not compile), or the backend shares it
///   (make_backend(name, std::shared_ptr<const Scene>)), and the scene lives until its last
///   owner lets go;
/// - scenes that move: Scene::set_vertices, set_transform, add_* and remove_* change a scene;
///   Backend::update() then brings a backend up to date (refit, instance level, rebuild of what
///   was added), and until then tracing throws rp::Error (core/backend.h, docs/updates.md);
/// - a Reference copies what it needs: the scene may go away once it is built;
/// - render, diff_hits, primary_rays and the other functions read their arguments during the
///   call only and return values the caller owns.
///
/// Errors: setup calls (loading, building, file I/O, bad settings) throw rp::Error, whose
/// what() is one line naming the file, value or name at fault; tracing calls throw only for a
/// backend whose scene changed since its last update().
/// Threads: a backend and a Reference may be queried from many threads at once; a scene's
/// changes and Backend::update() must not overlap tracing; the *_parallel functions, render,
/// Reference over spans and the backends' builds use every core unless an rp::ThreadLimit
/// is alive (`const rp::ThreadLimit limit(1);`), and rp::max_threads() says how many they
/// may use (core/thread_limit.h).

#include "analysis/diff.h"
#include "analysis/raygen.h"
#include "analysis/reference.h"
#include "backends/registry.h"
#include "base/error_type.h"
#include "core/backend.h"
#include "core/ray.h"
#include "core/scene.h"
#include "core/thread_limit.h"
#include "io/loaders/load.h"
#include "io/rayfile.h"
#include "raypack/version.h"
#include "render/camera.h"
#include "render/image_io.h"
#include "render/render.h"
