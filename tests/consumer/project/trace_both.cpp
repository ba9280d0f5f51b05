// A program outside raypack built against the installed package: a scene from arrays (or
// from the file named by the argument), the same camera rays through the simd and embree
// backends, their hits diffed with the double-precision reference as arbiter. Exits 0 when the
// backends agree on every ray, 1 when not, 77 when this CPU cannot run the simd backend.
#include <raypack/raypack.h>

#include <cstdio>
#include <cstring>
#include <memory>
#include <vector>

int main(int argc, char** argv) {
  if (std::strcmp(rp::version(), RAYPACK_FOUND_VERSION) != 0) {
    std::fprintf(stderr, "runs with raypack %s, built against %s\n", rp::version(), RAYPACK_FOUND_VERSION);
    return 1;
  }
  std::shared_ptr<const rp::Scene> scene;
  try {
    if (argc > 1) {
      scene = std::make_shared<const rp::Scene>(rp::load_scene(argv[1]));
    } else {  // a square of two triangles at z = 0 and a sphere in front of it
      rp::Scene arrays;
      rp::TriangleMesh square;
      square.positions = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
      square.indices = {0, 1, 2, 0, 2, 3};
      arrays.add_mesh(std::move(square));
      arrays.add_sphere({.center = {0.3f, 0.2f, 0.5f}, .radius = 0.25f, .material = 0});
      scene = std::make_shared<const rp::Scene>(std::move(arrays));
    }
  } catch (const rp::Error& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
  // Camera rays in 4x2-pixel packets, so every 8 consecutive rays form a coherent packet.
  const rp::RaySet camera = rp::primary_rays(*scene, 128, 96);
  std::vector<std::vector<rp::Hit>> hits;
  for (const char* name : {"simd", "embree"}) {
    if (const auto problem = rp::check_method(name, "default")) {
      std::fprintf(stderr, "%s\n", problem->message.c_str());
      return 77;
    }
    // The backend shares the scene, which lives as long as the backend does.
    const std::unique_ptr<rp::Backend> backend = rp::make_backend(name, scene);
    rp::intersect_parallel(*backend, camera.rays, hits.emplace_back(camera.rays.size()), rp::Coherence::coherent);
  }
  std::vector<rp::ReferenceHit> reference(camera.rays.size());
  rp::Reference(*scene).intersect(camera.rays, reference);
  const rp::DiffResult d = rp::diff_hits(*scene, camera.rays, hits[0], hits[1], reference, rp::DiffOptions{});
  std::printf("%s", rp::format_table(d, "simd/default", "embree/default").c_str());
  size_t hit_count = 0;
  for (const rp::Hit& h : hits[0]) hit_count += h.hit();
  std::printf("%zu of %zu rays hit\n", hit_count, camera.rays.size());
  return hit_count > 0 && d.agreement() == 1.0 ? 0 : 1;
}
