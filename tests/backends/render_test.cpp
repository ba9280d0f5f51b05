// The renderer over real backends: the lecture notes' adaptive sampling, the two backends' images,
// Whitted refraction through a glass sphere.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "backends/registry.h"
#include "render/camera.h"
#include "render/render.h"
#include "tests/support/scenes.h"

namespace rp {
namespace {

RenderSettings settings(int w, int h) {
  RenderSettings st;
  st.width = w;
  st.height = h;
  return st;
}

/// A plane seen from above (a flat region) and a sphere against the sky (an edge).
Scene plane_only() {
  Scene s;
  s.add_plane({{0, 1, 0}, 0, 0});
  s.add_light(DirectionalLight{{0, -1, 0}, Vec3f{1.0f}});
  s.set_camera({{0, 5, 0.001f}, {0, 0, 0}, {0, 0, -1}, 30.0f});
  return s;
}
Scene sphere_on_sky() {
  Scene s;
  s.add_sphere({{0, 0, 0}, 1, 0});
  s.add_light(DirectionalLight{{0, -1, -1}, Vec3f{1.0f}});
  s.set_camera({{0, 0, 4}, {0, 0, 0}, {0, 1, 0}, 40.0f});
  return s;
}

TEST(AdaptiveSampling, TracesFewerRaysThanUniformOnAFlatRegionAndMoreAtAnEdge) {
  const int w = 32, h = 32;
  RenderSettings st = settings(w, h);
  st.sampler = Sampler::adaptive;
  st.adaptive_depth = 3;
  st.adaptive_threshold = 0.05f;
  auto flat_scene = plane_only();
  auto flat_backend = make_backend("embree", flat_scene);
  const RenderStats flat = render(flat_scene, *flat_backend, Camera(*flat_scene.camera(), w, h), st).stats;
  // Corners only: (w+1)(h+1) for one 32x32 image split into 16x16 tiles (borders traced by each tile).
  EXPECT_EQ(flat.primary, uint64_t(4 * 17 * 17));
  EXPECT_LT(flat.primary, uint64_t(w * h * 4));  // uniform 2x2 sampling
  auto edge_scene = sphere_on_sky();
  auto edge_backend = make_backend("embree", edge_scene);
  const RenderStats edge = render(edge_scene, *edge_backend, Camera(*edge_scene.camera(), w, h), st).stats;
  EXPECT_GT(edge.primary, flat.primary + uint64_t(w));  // subdivided along the silhouette
  EXPECT_LT(edge.primary, edge.uniform_primary);
}

TEST(Render, TheTwoBackendsImagesDifferVisiblyOnlyAtAFewEdgePixels) {
  const Scene scene = make_default_scene();
  const auto available = available_backends();
  if (std::find(available.begin(), available.end(), "simd") == available.end())
    GTEST_SKIP() << "the simd backend is not available on this CPU";
  const int w = 160, h = 120;
  const Camera cam(*scene.camera(), w, h);
  const Image a = render(scene, *make_backend("embree", scene), cam, settings(w, h)).image;
  const Image b = render(scene, *make_backend("simd", scene), cam, settings(w, h)).image;
  // The backends' t and (u, v) differ in the last bits, so shading differs below 1e-3 almost
  // everywhere; a visible difference (more than 1/255 in a channel) comes from a different
  // primitive: a tie on an edge, or a shadow ray grazing a silhouette.
  size_t differ = 0, visible = 0;
  for (size_t p = 0; p < size_t(w) * size_t(h); ++p) {
    float d = 0.0f;
    for (int c = 0; c < 3; ++c) d = std::max(d, std::abs(a.rgb[3 * p + size_t(c)] - b.rgb[3 * p + size_t(c)]));
    differ += d > 0.0f;
    visible += d > 1.0f / 255.0f;
  }
  RecordProperty("differing_pixels", int(differ));
  RecordProperty("visibly_differing_pixels", int(visible));
  std::printf("pixels differing between embree and simd: %zu in the last bits, %zu by more than 1/255 (of %d)\n",
              differ, visible, w * h);
  EXPECT_LE(visible, size_t(w * h) / 1000) << visible << " of " << w * h << " pixels differ visibly";
}

/// Pixels of a and b differing in some channel at all, and by more than 1/255.
struct PixelDifferences {
  size_t differ = 0, visible = 0;
};
PixelDifferences compare(const Image& a, const Image& b) {
  PixelDifferences d;
  for (size_t p = 0; p < a.rgb.size() / 3; ++p) {
    float m = 0.0f;
    for (int c = 0; c < 3; ++c) m = std::max(m, std::abs(a.rgb[3 * p + size_t(c)] - b.rgb[3 * p + size_t(c)]));
    d.differ += m > 0.0f;
    d.visible += m > 1.0f / 255.0f;
  }
  return d;
}

TEST(Render, InstancesShadeAsTheirTrianglesBakedIntoTheWorld) {
  // The instanced test scene (rotated, unevenly scaled and mirrored placements of a closed
  // mesh and a soup, vertex normals on the ball) against the same triangles baked into world
  // meshes, with lights and shadows: the same picture on every backend but for pixels where
  // rounding picks another edge or shadow boundary.
  Scene scene = test::instanced_scene();
  scene.add_light(PointLight{{2.0f, 3.0f, 2.5f}, {12.0f, 12.0f, 12.0f}});
  scene.add_light(DirectionalLight{normalize(Vec3f{-0.3f, -1.0f, -0.4f}), Vec3f{0.4f}});
  const Scene flat = test::flattened(scene);
  const int w = 160, h = 120;
  const Camera cam(frame_bounds(scene.bounds()), w, h);
  for (const std::string& name : available_backends()) {
    const Image a = render(scene, *make_backend(name, scene), cam, settings(w, h)).image;
    const Image b = render(flat, *make_backend(name, flat), cam, settings(w, h)).image;
    const PixelDifferences d = compare(a, b);
    std::printf("%s: instanced against flattened: %zu pixels differ in the last bits, %zu by more than 1/255 (of %d)\n",
                name.c_str(), d.differ, d.visible, w * h);
    EXPECT_LE(d.visible, size_t(w * h) / 1000) << name;
  }
}

TEST(Aovs, DepthNormalAndPrimitiveOfAKnownScene) {
  // Looking straight down -z at the plane z = -3 with a sphere of radius 1 at the centre.
  Scene s;
  s.add_plane({{0, 0, 1}, 3, 0});
  s.add_sphere({{0, 0, -1}, 1, 0});
  const Camera cam({{0, 0, 2}, {0, 0, 0}, {0, 1, 0}, 60.0f}, 9, 9);
  for (const std::string& name : available_backends()) {
    const Aovs a = render_aovs(s, *make_backend(name, s), cam);
    const size_t centre = 4 * 9 + 4, corner = 0;
    EXPECT_NEAR(a.depth[centre], 2.0f, 1e-5f) << name;  // eye z = 2 to the sphere top z = 0
    EXPECT_EQ(a.prim_id[centre], s.sphere_base()) << name;
    EXPECT_NEAR(a.normal[3 * centre + 2], 1.0f, 1e-5f) << name;
    EXPECT_EQ(a.prim_id[corner], s.plane_base()) << name;
    const Ray r = cam.generate(0.5f, 0.5f);
    EXPECT_NEAR(a.depth[corner], 5.0f / -r.dir.z, 1e-4f) << name;  // to z = -3 along a unit ray
    EXPECT_NEAR(a.shading_normal[3 * corner + 2], 1.0f, 1e-6f) << name;
    EXPECT_EQ(a.instance_id[centre], kNoInstance) << name;
  }
}

TEST(Aovs, AnInstancesPixelsNameTheInstance) {
  // One triangle placed twice, side by side: the left half of the image sees instance 0,
  // the right half instance 1, both with the mesh's own prim id 0.
  Scene s;
  TriangleMesh quad;
  quad.name = "quad";
  quad.positions = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
  quad.indices = {0, 1, 2, 0, 2, 3};
  const uint32_t m = s.add_instanced_mesh(quad);
  Affine3f left, right;
  left.m[0][3] = -1.0f;
  right.m[0][3] = 1.0f;
  s.add_instance(m, left);
  s.add_instance(m, right);
  const Camera cam({{0, 0, 3}, {0, 0, 0}, {0, 1, 0}, 60.0f}, 8, 4);
  for (const std::string& name : available_backends()) {
    const Aovs a = render_aovs(s, *make_backend(name, s), cam);
    EXPECT_EQ(a.instance_id[1 * 8 + 2], 0u) << name;  // x = -1.3 at the quads
    EXPECT_EQ(a.instance_id[2 * 8 + 5], 1u) << name;  // x = +1.3
    EXPECT_LT(a.prim_id[2 * 8 + 5], 2u) << name;
    EXPECT_NEAR(a.depth[1 * 8 + 2] * std::abs(cam.generate(2.5f, 1.5f).dir.z), 3.0f, 1e-4f) << name;
  }
}

TEST(Fresnel, MatchesTheClosedForms) {
  EXPECT_NEAR(fresnel_dielectric(1.0f, 1.0f, 1.5f), 0.04f, 1e-6f);  // ((n1-n2)/(n1+n2))^2
  EXPECT_NEAR(fresnel_dielectric(1.0f, 1.5f, 1.0f), 0.04f, 1e-6f);
  EXPECT_EQ(fresnel_dielectric(0.1f, 1.5f, 1.0f), 1.0f);  // beyond the critical angle: total reflection
  EXPECT_NEAR(fresnel_dielectric(0.0f, 1.0f, 1.5f), 1.0f, 1e-6f);  // grazing
  EXPECT_NEAR(fresnel_dielectric(0.7f, 1.0f, 1.0f), 0.0f, 1e-7f);  // no interface
}

TEST(Refraction, AGlassSphereInvertsWhatIsBehindIt) {
  // A glass ball in front of a plane whose top half is lit and bottom half dark: seen
  // through the ball (a converging lens), the image flips, so the ball's top shows dark.
  Scene s;
  const uint32_t glass = s.add_material({.name = "glass", .diffuse = {0, 0, 0}, .specular = {1, 1, 1}, .ior = 1.5f,
                                         .opacity = 0.0f});
  const uint32_t white = s.add_material({.name = "white", .diffuse = {1, 1, 1}});
  const uint32_t black = s.add_material({.name = "black", .diffuse = {0, 0, 0}});
  s.add_sphere({{0, 0, 0}, 1, glass});
  TriangleMesh top, bottom;
  top.name = "top";
  top.positions = {{-20, 0, -6}, {20, 0, -6}, {20, 20, -6}, {-20, 20, -6}};
  top.indices = {0, 1, 2, 0, 2, 3};
  top.material = white;
  bottom = top;
  bottom.name = "bottom";
  bottom.positions = {{-20, -20, -6}, {20, -20, -6}, {20, 0, -6}, {-20, 0, -6}};
  bottom.material = black;
  s.add_mesh(top);
  s.add_mesh(bottom);
  s.add_light(DirectionalLight{{0, 0, -1}, Vec3f{1.0f}});
  s.set_camera({{0, 0, 5}, {0, 0, 0}, {0, 1, 0}, 30.0f});
  RenderSettings st = settings(41, 41);
  st.max_depth = 6;
  const RenderResult r = render(s, *make_backend("embree", s), Camera(*s.camera(), 41, 41), st);
  auto lum = [&](int x, int y) {
    const float* p = &r.image.rgb[(size_t(y) * 41 + size_t(x)) * 3];
    return p[0] + p[1] + p[2];
  };
  EXPECT_GT(r.stats.refraction, 0u);
  // Outside the ball: the plane as it is (top lit, bottom dark).
  EXPECT_GT(lum(20, 1), lum(20, 39));
  // Through the ball, above and below its centre: flipped.
  EXPECT_LT(lum(20, 14), lum(20, 26));
}

}  // namespace
}  // namespace rp
