// A glTF with a node hierarchy against the same triangles flattened into an OBJ, on every
// backend: the file is written by the test (tinygltf's writer, tests/support/gltf_files.h),
// the OBJ from the test's own composition of the nodes' transforms. Rays aimed inside every
// triangle and past the scene give the same hit or miss and t within 1e-5 (relative) in both,
// wherever the double-precision oracle finds the ray well-conditioned; the two render the same
// picture (a pixel may differ in its last bits, and rarely visibly, where rounding picks
// another edge or shadow boundary).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "backends/registry.h"
#include "io/loaders/load.h"
#include "oracle.h"
#include "render/camera.h"
#include "render/render.h"
#include "tests/support/gltf_files.h"
#include "tests/support/temp_dir.h"

namespace rp {
namespace {

/// Rays from four eyes around the scene at points inside each triangle (barycentric weights
/// at least 0.15), and rays past the scene's box.
std::vector<Ray> rays_at(const std::vector<std::array<Vec3d, 3>>& triangles, const Box3f& box) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.15, 0.7);
  const Vec3f c = box.center();
  const float r = length(box.extent());
  const Vec3f eyes[] = {c + Vec3f(0.3f, 0.4f, 1.0f) * r, c + Vec3f(-1.0f, 0.6f, 0.2f) * r,
                        c + Vec3f(0.2f, -0.8f, -0.7f) * r, c + Vec3f(0.9f, 0.1f, -0.6f) * r};
  std::vector<Ray> rays;
  for (const Vec3f& eye : eyes) {
    for (const auto& t : triangles)
      for (int k = 0; k < 3; ++k) {
        double a = u(rng), b = u(rng);
        if (a + b > 0.85) a *= 0.85 / (a + b), b *= 0.85 / (a + b);
        const Vec3d p = t[0] * (1.0 - a - b) + t[1] * a + t[2] * b;
        rays.push_back({eye, 0.0f, Vec3f(p) - eye, std::numeric_limits<float>::infinity()});
      }
    for (int k = 0; k < 64; ++k)  // past the box
      rays.push_back({eye, 0.0f, (c + Vec3f(float(u(rng)), float(u(rng)), 1.0f) * (3.0f * r)) - eye,
                      std::numeric_limits<float>::infinity()});
  }
  return rays;
}

TEST(GltfScene, HitsTheSameAsItsTrianglesFlattenedIntoAnObjOnEveryBackend) {
  test::TempDir tmp;
  const test::HierarchyGltf h = test::hierarchy_gltf();
  test::write_gltf(h.model, tmp / "scene.gltf", test::GltfForm::embedded);
  test::write_gltf(h.model, tmp / "scene.glb", test::GltfForm::binary);
  std::ofstream(tmp / "flat.obj") << test::obj_of(h.world_triangles);
  const Scene flat = load_scene(tmp / "flat.obj");
  const std::vector<Ray> rays = rays_at(h.world_triangles, flat.bounds());
  const float delta = 1e-4f * max_component(abs(flat.bounds().extent()));
  std::vector<uint8_t> ambiguous(rays.size());
  size_t excused = 0;
  for (size_t i = 0; i < rays.size(); ++i) excused += ambiguous[i] = test::oracle_ambiguous(flat, rays[i], delta);
  EXPECT_LE(excused, rays.size() / 100) << "rays aimed inside triangles should rarely be ill-conditioned";
  for (const std::string& file : {std::string("scene.gltf"), std::string("scene.glb")}) {
    const Scene gltf = load_scene(tmp / file);
    ASSERT_EQ(gltf.instances().size(), 3u) << file;
    for (const std::string& name : available_backends()) {
      const auto a = make_backend(name, gltf), b = make_backend(name, flat);
      for (Coherence coh : {Coherence::coherent, Coherence::incoherent}) {
        std::vector<Hit> ha(rays.size()), hb(rays.size());
        a->intersect(rays, ha, coh);
        b->intersect(rays, hb, coh);
        size_t hits = 0, instance_hits = 0, failures = 0;
        for (size_t i = 0; i < rays.size() && failures < 10; ++i) {
          hits += hb[i].hit();
          instance_hits += ha[i].instance_id != kNoInstance;
          if (ambiguous[i]) continue;
          const bool same = ha[i].hit() == hb[i].hit() &&
                            (!ha[i].hit() || std::abs(double(ha[i].t) - double(hb[i].t)) <= 1e-5 * double(hb[i].t));
          if (same) continue;
          ++failures;
          ADD_FAILURE() << file << " " << name << " ray " << i << ": glTF prim " << ha[i].prim_id << " instance "
                        << ha[i].instance_id << " t " << ha[i].t << ", OBJ prim " << hb[i].prim_id << " t " << hb[i].t;
        }
        // Of the rays aimed inside a triangle (4 eyes x 3 per triangle) nearly all hit (one
        // triangle may hide another), those aimed at the three placements of "pair" (2
        // triangles each) mostly through its instances.
        const size_t aimed = 12 * h.world_triangles.size();
        EXPECT_GE(hits, aimed * 9 / 10) << file << " " << name;
        EXPECT_GE(instance_hits, size_t(12 * 6 * 8 / 10)) << file << " " << name;
      }
    }
  }
}

TEST(GltfScene, RendersTheSamePictureAsItsTrianglesFlattenedIntoAnObj) {
  // Without materials, so that both are the default grey; the default lights placed from
  // the bounds, the same in both.
  test::TempDir tmp;
  test::HierarchyGltf h = test::hierarchy_gltf();
  h.model.materials.clear();
  for (tinygltf::Mesh& m : h.model.meshes)
    for (tinygltf::Primitive& p : m.primitives) p.material = -1;
  test::write_gltf(h.model, tmp / "grey.glb", test::GltfForm::binary);
  std::ofstream(tmp / "flat.obj") << test::obj_of(h.world_triangles);
  const Scene gltf = load_scene(tmp / "grey.glb"), flat = load_scene(tmp / "flat.obj");
  const int w = 160, hgt = 120;
  const Camera cam(frame_bounds(flat.bounds()), w, hgt);
  RenderSettings st;
  st.width = w;
  st.height = hgt;
  for (const std::string& name : available_backends()) {
    const Image a = render(gltf, *make_backend(name, gltf), cam, st).image;
    const Image b = render(flat, *make_backend(name, flat), cam, st).image;
    size_t visible = 0, covered = 0;
    for (size_t p = 0; p < a.rgb.size() / 3; ++p) {
      float d = 0.0f;
      for (int c = 0; c < 3; ++c) d = std::max(d, std::abs(a.rgb[3 * p + size_t(c)] - b.rgb[3 * p + size_t(c)]));
      visible += d > 1.0f / 255.0f;
    }
    const Aovs aa = render_aovs(gltf, *make_backend(name, gltf), cam), ab = render_aovs(flat, *make_backend(name, flat), cam);
    for (size_t p = 0; p < aa.depth.size(); ++p) {
      covered += std::isfinite(ab.depth[p]);
      if (std::isfinite(aa.depth[p]) != std::isfinite(ab.depth[p])) ++visible;
    }
    std::printf("%s: glTF against flattened OBJ: %zu of %d pixels differ visibly (%zu pixels covered)\n", name.c_str(),
                visible, w * hgt, covered);
    EXPECT_GT(covered, size_t(w * hgt) / 25) << name << ": the scene must fill part of the picture (5%)";
    EXPECT_LE(visible, size_t(w * hgt) / 500) << name;
  }
}

}  // namespace
}  // namespace rp
