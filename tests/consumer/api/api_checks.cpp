// A program outside raypack, built against the installed package, that checks what the
// library promises besides tracing: the version macros equal the library it runs with and the
// version the package was found at; under rp::ThreadLimit(1) every parallel call runs on its
// caller's thread alone and returns what an unlimited call returns, bit for bit; and the
// headers carry none of the library's own check macros. The argument picks the scene: none, a
// grid of triangles and a row of spheres from arrays; "default", the embedded default scene.
// Exits 0 when every check holds, 1 naming each that does not.
#include <raypack/raypack.h>

#if defined(RP_CHECK) || defined(RP_DCHECK)
#error "<raypack/raypack.h> defines RP_CHECK or RP_DCHECK, checks internal to raypack"
#endif
#if !defined(RAYPACK_VERSION_MAJOR) || RAYPACK_VERSION_MAJOR < 0 || RAYPACK_VERSION_MINOR < 0 || \
    RAYPACK_VERSION_PATCH < 0
#error "<raypack/raypack.h> has no version macros the preprocessor can compare"
#endif

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <mutex>
#include <set>
#include <span>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace {

int failures = 0;

void check(bool holds, const std::string& what) {
  if (holds) return;
  std::fprintf(stderr, "api_checks: %s\n", what.c_str());
  ++failures;
}

/// A backend of the program's own around a real one (rp::ForwardingBackend passes every call
/// on) that records the threads its batches arrive on, so that the program sees where a
/// parallel call ran.
class ThreadRecorder final : public rp::ForwardingBackend {
 public:
  ThreadRecorder(const rp::Scene& scene, std::unique_ptr<rp::Backend> inner)
      : ForwardingBackend(scene, std::move(inner)) {}

  /// The threads of the batches since the last call, and none from then on.
  std::set<std::thread::id> take_threads() const {
    const std::lock_guard lock(mutex_);
    return std::exchange(threads_, {});
  }

 protected:
  void trace_closest(std::span<const rp::Ray> rays, std::span<rp::Hit> hits,
                     rp::Coherence coherence) const noexcept override {
    record();
    ForwardingBackend::trace_closest(rays, hits, coherence);
  }
  void trace_any(std::span<const rp::Ray> rays, std::span<uint8_t> occluded,
                 rp::Coherence coherence) const noexcept override {
    record();
    ForwardingBackend::trace_any(rays, occluded, coherence);
  }

 private:
  void record() const {
    const std::lock_guard lock(mutex_);
    threads_.insert(std::this_thread::get_id());
  }

  mutable std::mutex mutex_;
  mutable std::set<std::thread::id> threads_;
};

/// A 64 x 64 grid of squares (two triangles each) at z = 0 and a row of spheres in front.
rp::Scene arrays_scene() {
  rp::Scene scene;
  rp::TriangleMesh grid;
  constexpr int n = 64;
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x) grid.positions.push_back({2.0f * x / n - 1, 2.0f * y / n - 1, 0});
  for (uint32_t y = 0; y < n; ++y)
    for (uint32_t x = 0; x < n; ++x) {
      const uint32_t a = y * (n + 1) + x, b = a + 1, c = a + n + 2, d = a + n + 1;
      grid.indices.insert(grid.indices.end(), {a, b, c, a, c, d});
    }
  scene.add_mesh(std::move(grid));
  for (int i = 0; i < 5; ++i) scene.add_sphere({.center = {-0.8f + 0.4f * i, 0, 0.3f}, .radius = 0.15f, .material = 0});
  return scene;
}

/// What every parallel call of the API returned, for comparing two runs bit for bit.
struct Results {
  std::vector<rp::Hit> hits;
  std::vector<uint8_t> occluded;
  std::vector<rp::ReferenceHit> reference;
  std::vector<float> image;
};

/// intersect_parallel, occluded_parallel, a Reference built and queried over a span, and a
/// render: every parallel call a program makes, with the threads the backend's batches arrived on.
Results run_all(const rp::Scene& scene, const ThreadRecorder& backend, const rp::RaySet& primary,
                std::set<std::thread::id>& threads) {
  Results r;
  r.hits.resize(primary.rays.size());
  rp::intersect_parallel(backend, primary.rays, r.hits, rp::Coherence::coherent);
  const rp::RaySet shadow = rp::shadow_rays(scene, primary, r.hits);
  r.occluded.resize(shadow.rays.size());
  rp::occluded_parallel(backend, shadow.rays, r.occluded, rp::Coherence::incoherent);
  r.reference.resize(primary.rays.size());
  rp::Reference(scene).intersect(primary.rays, r.reference);
  const rp::RenderSettings settings{.width = 64, .height = 48};
  const rp::Camera camera(scene.camera() ? *scene.camera() : rp::frame_bounds(scene.bounds()), settings.width,
                          settings.height);
  r.image = rp::render(scene, backend, camera, settings).image.rgb;
  threads = backend.take_threads();
  return r;
}

template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

bool same_reference(const std::vector<rp::ReferenceHit>& a, const std::vector<rp::ReferenceHit>& b) {
  return std::equal(a.begin(), a.end(), b.begin(), b.end(), [](const rp::ReferenceHit& x, const rp::ReferenceHit& y) {
    return x.prim_id == y.prim_id && x.instance_id == y.instance_id && std::memcmp(&x.t, &y.t, sizeof(double)) == 0 &&
           std::memcmp(&x.u, &y.u, sizeof(double)) == 0 && std::memcmp(&x.v, &y.v, sizeof(double)) == 0;
  });
}

void check_versions() {
  const std::string numbers = std::to_string(RAYPACK_VERSION_MAJOR) + "." + std::to_string(RAYPACK_VERSION_MINOR) +
                              "." + std::to_string(RAYPACK_VERSION_PATCH);
  check(numbers == RAYPACK_VERSION_STRING, "the version macros say " + numbers + " and " + RAYPACK_VERSION_STRING);
  check(std::strcmp(rp::version(), RAYPACK_VERSION_STRING) == 0,
        std::string("runs with raypack ") + rp::version() + ", compiled against headers of " + RAYPACK_VERSION_STRING);
  check(
      std::strcmp(RAYPACK_FOUND_VERSION, RAYPACK_VERSION_STRING) == 0,
      std::string("the package was found at ") + RAYPACK_FOUND_VERSION + ", its headers say " + RAYPACK_VERSION_STRING);
}

void check_limit_rules() {
  const int cores = rp::max_threads();
  check(cores >= 1, "max_threads() is " + std::to_string(cores) + " without a limit");
  {
    const rp::ThreadLimit one(1);
    check(rp::max_threads() == 1, "max_threads() is " + std::to_string(rp::max_threads()) + " under a limit of 1");
    const rp::ThreadLimit two(2), none(0);  // neither lifts the smaller limit
    check(rp::max_threads() == 1, "a limit of 2 or 0 inside a limit of 1 gives " + std::to_string(rp::max_threads()));
  }
  check(rp::max_threads() == cores, "max_threads() is " + std::to_string(rp::max_threads()) +
                                        " after the limits ended, " + std::to_string(cores) + " before");
  bool refused = false;
  try {
    const rp::ThreadLimit negative(-1);
  } catch (const rp::Error& e) {
    refused = std::string(e.what()).find("-1") != std::string::npos;
  }
  check(refused, "ThreadLimit(-1) did not throw an rp::Error naming -1");
}

/// The grid of arrays_scene() in the program's own interleaved buffer (position and a tag per
/// vertex, 16 bytes), shared with a scene (add_shared_mesh): the scene points at the buffer,
/// the hits equal those over the scene's copy, and a move written in place reaches an updated
/// backend (vertices_changed).
void check_shared_mesh() {
  struct Vertex {
    rp::Vec3f position;
    uint32_t tag;
  };
  const rp::Scene copy = arrays_scene();
  const rp::MeshView& grid = copy.meshes()[0];
  std::vector<Vertex> vertices;
  for (const rp::Vec3f& p : grid.positions) vertices.push_back({p, 7});
  const std::vector<rp::TriangleIndices> triangles(grid.triangles.begin(), grid.triangles.end());
  rp::Scene shared;
  shared.add_shared_mesh({.name = "grid",
                          .positions = {&vertices[0].position, vertices.size(), sizeof(Vertex)},
                          .triangles = triangles,
                          .normals = {},
                          .uvs = {},
                          .face_materials = {},
                          .material = 0});
  for (const rp::Sphere& s : copy.spheres()) shared.add_sphere(s);
  check(shared.meshes()[0].positions.data() == &vertices[0].position, "add_shared_mesh copied the positions");
  const rp::RaySet primary = rp::primary_rays(copy, 64, 48);
  std::vector<rp::Hit> a(primary.rays.size()), b(primary.rays.size());
  for (const char* name : {"embree", "simd"}) {
    if (rp::check_method(name, "default")) continue;
    const auto over_copy = rp::make_backend(name, copy);
    const auto over_buffer = rp::make_backend(name, shared);
    rp::intersect_parallel(*over_copy, primary.rays, a, rp::Coherence::coherent);
    rp::intersect_parallel(*over_buffer, primary.rays, b, rp::Coherence::coherent);
    check(same_bits(a, b), std::string(name) + ": other hits over the shared buffer than over the copy");
    for (Vertex& v : vertices) v.position.z -= 0.5f;  // the program moves its grid back
    shared.vertices_changed(0);
    over_buffer->update();
    rp::intersect_parallel(*over_buffer, primary.rays, b, rp::Coherence::coherent);
    size_t on_grid = 0, farther = 0;  // the camera looks along -z: every grid hit is farther now
    for (size_t i = 0; i < a.size(); ++i)
      if (a[i].prim_id < grid.triangle_count() && b[i].prim_id < grid.triangle_count()) {
        ++on_grid;
        farther += b[i].t > a[i].t;
      }
    check(on_grid > 0 && farther == on_grid, std::string(name) + ": " + std::to_string(farther) + " of " +
                                                 std::to_string(on_grid) +
                                                 " hits on the grid farther after it moved back (vertices_changed)");
    for (Vertex& v : vertices) v.position.z += 0.5f;
    shared.vertices_changed(0);
  }
}

}  // namespace

int main(int argc, char** argv) {
  check_versions();
  check_limit_rules();
  if (const auto problem = rp::check_method("embree", "default")) {
    std::fprintf(stderr, "%s\n", problem->message.c_str());
    return 77;
  }
  try {
    check_shared_mesh();
    const rp::Scene scene = argc > 1 ? rp::load_scene(argv[1]) : arrays_scene();
    const ThreadRecorder backend(scene, rp::make_backend("embree", scene));
    const rp::RaySet primary = rp::primary_rays(scene, 256, 192);  // 12 chunks of intersect_parallel
    std::set<std::thread::id> all_threads, one_thread;
    const Results all = run_all(scene, backend, primary, all_threads);
    Results one;
    {
      const rp::ThreadLimit limit(1);
      one = run_all(scene, backend, primary, one_thread);
    }
    check(one_thread == std::set<std::thread::id>{std::this_thread::get_id()},
          "under a limit of 1 the backend was called on " + std::to_string(one_thread.size()) +
              " threads, not the caller's alone");
    check(same_bits(one.hits, all.hits), "intersect_parallel: other hits under a limit of 1");
    check(same_bits(one.occluded, all.occluded), "occluded_parallel: other answers under a limit of 1");
    check(same_reference(one.reference, all.reference), "Reference: other hits under a limit of 1");
    check(same_bits(one.image, all.image), "render: another image under a limit of 1");
    size_t hit_count = 0;
    for (const rp::Hit& h : all.hits) hit_count += h.hit();
    check(hit_count > 0, "no primary ray hit the scene");
    std::printf(
        "%zu of %zu primary rays hit; the backend's calls came from %zu thread(s) without a limit "
        "(max_threads %d), from %zu under a limit of 1\n",
        hit_count, primary.rays.size(), all_threads.size(), rp::max_threads(), one_thread.size());
  } catch (const rp::Error& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
  return failures == 0 ? 0 : 1;
}
