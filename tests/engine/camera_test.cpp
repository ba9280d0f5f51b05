// Pinhole camera against the lecture notes' pixel mapping, and the sample pattern.

#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <random>
#include <set>

#include "base/error.h"
#include "render/camera.h"
#include "render/render.h"

namespace rp {
namespace {

TEST(Camera, RaysFollowTheSeedsPixelMapping) {
  // Camera at the origin looking down -z: u = +x, v = +y, w = -z.
  const CameraDesc d{{0, 0, 0}, {0, 0, -1}, {0, 1, 0}, 60.0f};
  const int nx = 64, ny = 48;
  const Camera cam(d, nx, ny);
  const double ym = std::tan(60.0 * kPi / 360.0), xm = double(nx) / ny * ym;
  for (int i : {0, 17, 63})
    for (int row : {0, 20, 47}) {
      const int j = ny - 1 - row;  // the lecture notes count j from the bottom
      const double x = ((i + 0.5) / nx * 2 - 1) * xm, y = ((j + 0.5) / ny * 2 - 1) * ym;
      const Vec3d want = normalize(Vec3d{x, y, -1.0});
      const Ray r = cam.generate(i + 0.5f, row + 0.5f);
      EXPECT_EQ(r.org, (Vec3f{0, 0, 0}));
      EXPECT_NEAR(r.dir.x, want.x, 1e-6);
      EXPECT_NEAR(r.dir.y, want.y, 1e-6);
      EXPECT_NEAR(r.dir.z, want.z, 1e-6);
    }
}

TEST(Camera, CentreRayLooksAtTheTarget) {
  const CameraDesc d{{1, 2, 3}, {4, 6, 3}, {0, 0, 1}, 45.0f};
  const Camera cam(d, 10, 10);
  const Ray r = cam.generate(5.0f, 5.0f);
  EXPECT_NEAR(r.dir.x, 0.6f, 1e-6);
  EXPECT_NEAR(r.dir.y, 0.8f, 1e-6);
  EXPECT_NEAR(r.dir.z, 0.0f, 1e-6);
}

TEST(Camera, DegeneratePlacementsAreErrors) {
  EXPECT_THROW(Camera(CameraDesc{{0, 0, 0}, {0, 0, 0}, {0, 1, 0}, 45}, 4, 4), Error);
  EXPECT_THROW(Camera(CameraDesc{{0, 0, 0}, {0, 1, 0}, {0, 1, 0}, 45}, 4, 4), Error);
  EXPECT_THROW(Camera(CameraDesc{{0, 0, 0}, {0, 0, 1}, {0, 1, 0}, 180}, 4, 4), Error);
  EXPECT_THROW(Camera(CameraDesc{{0, 0, 0}, {0, 0, 1}, {0, 1, 0}, 45}, 0, 4), Error);
}

/// generate() then project() returns the image position, for every model with an inverse.
void expect_round_trip(const CameraDesc& d, int w, int h) {
  const Camera cam(d, w, h);
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> ux(0.0f, float(w)), uy(0.0f, float(h));
  int checked = 0;
  for (int i = 0; i < 2000; ++i) {
    const float px = ux(rng), py = uy(rng);
    const Ray r = cam.generate(px, py);
    if (r.tnear > r.tfar) continue;  // fisheye: outside the image circle
    const std::optional<Vec2f> back = cam.project(r.dir);
    ASSERT_TRUE(back.has_value()) << px << ", " << py;
    EXPECT_NEAR(back->x, px, 2e-3f * float(w)) << px << ", " << py;
    EXPECT_NEAR(back->y, py, 2e-3f * float(h)) << px << ", " << py;
    EXPECT_NEAR(length(r.dir), 1.0f, 1e-5f);
    ++checked;
  }
  EXPECT_GT(checked, 1000);
}

TEST(Camera, FramingFollowsTheUpAxis) {
  // A tall box standing on z = 0 (a Z-up scan): framed from its front (-y) and a little above,
  // z up; Y up (the default) sees the same box from +z, y up.
  const Box3f box({-1, -1, 0}, {1, 1, 6});
  const CameraDesc z = frame_bounds(box, 2);
  EXPECT_EQ(z.up, Vec3f(0, 0, 1));
  EXPECT_EQ(z.look_at, box.center());
  EXPECT_LT(z.eye.y, box.lo.y);
  EXPECT_GT(z.eye.z, box.center().z);
  EXPECT_NEAR(z.eye.x, 0.0f, 1e-6f);
  const CameraDesc y = frame_bounds(box);
  EXPECT_EQ(y.up, Vec3f(0, 1, 0));
  EXPECT_GT(y.eye.z, box.hi.z);
  const Camera cam(z, 64, 64);  // a valid placement
  EXPECT_GT(dot(cam.generate(32.0f, 32.0f).dir, Vec3f(0, 1, 0)), 0.9f);  // looking along +y
}

TEST(Camera, EveryMappingRoundTrips) {
  CameraDesc d{{1, 2, 3}, {0, 1, -2}, {0, 1, 0}, 50.0f};
  expect_round_trip(d, 64, 48);
  d.model = CameraModel::panoramic;
  expect_round_trip(d, 128, 32);
  d.model = CameraModel::fisheye;
  for (float fov : {90.0f, 180.0f, 220.0f}) {
    d.fisheye_fov_degrees = fov;
    expect_round_trip(d, 64, 64);
  }
}

TEST(Camera, PanoramaCoversAFullTurnAroundTheUpAxis) {
  const Camera cam({{0, 0, 0}, {0, 0, -1}, {0, 1, 0}, 60.0f, CameraModel::panoramic}, 360, 90);
  // Left edge, centre and right edge of the middle row look back, ahead, back.
  EXPECT_NEAR(cam.generate(0.0f, 45.0f).dir.z, 1.0f, 1e-5f);
  EXPECT_NEAR(cam.generate(180.0f, 45.0f).dir.z, -1.0f, 1e-5f);
  EXPECT_NEAR(cam.generate(90.0f, 45.0f).dir.x, -1.0f, 1e-5f);   // a quarter turn left
  EXPECT_NEAR(cam.generate(270.0f, 45.0f).dir.x, 1.0f, 1e-5f);  // and right (u = w x up = +x)
}

TEST(Camera, FisheyeAngleGrowsLinearlyWithRadiusAndStopsAtTheCircle) {
  const Camera cam({{0, 0, 0}, {0, 0, -1}, {0, 1, 0}, 60.0f, CameraModel::fisheye, 180.0f}, 100, 100);
  for (float r : {0.0f, 10.0f, 25.0f, 40.0f, 49.9f}) {
    const Ray ray = cam.generate(50.0f + r, 50.0f);
    EXPECT_NEAR(std::acos(-ray.dir.z), r / 50.0f * float(kPi) / 2.0f, 1e-4f) << r;
  }
  const Ray outside = cam.generate(99.0f, 99.0f);
  EXPECT_GT(outside.tnear, outside.tfar) << "no ray outside the image circle";
}

TEST(Camera, ThinLensRaysOfAPixelMeetOnThePlaneInFocus) {
  CameraDesc d{{0, 1, 6}, {0, 1, 0}, {0, 1, 0}, 40.0f, CameraModel::thin_lens};
  d.aperture = 0.3f;
  d.focus_distance = 4.0f;
  const Camera cam(d, 64, 64);
  const Camera pin({{0, 1, 6}, {0, 1, 0}, {0, 1, 0}, 40.0f}, 64, 64);
  for (Vec2f px : {Vec2f{32.0f, 32.0f}, Vec2f{3.5f, 60.25f}, Vec2f{50.0f, 10.0f}}) {
    const Ray centre = pin.generate(px.x, px.y);
    const Vec3f focus = centre.at(4.0f / -centre.dir.z);  // the pinhole ray at depth 4 along w = -z
    for (Vec2f lens : {Vec2f{0.1f, 0.2f}, Vec2f{0.9f, 0.5f}, Vec2f{0.5f, 0.99f}, Vec2f{0.0f, 0.0f}}) {
      const Ray r = cam.generate(px.x, px.y, lens);
      EXPECT_LE(length(r.org - d.eye), d.aperture * 1.0001f) << "origin on the lens disk";
      const Vec3f p = r.at((r.org.z - 2.0f) / -r.dir.z);  // plane z = 6 - 4
      EXPECT_NEAR(length(p - focus), 0.0f, 1e-4f);
    }
    const Ray at_centre = cam.generate(px.x, px.y);  // the lens centre is the pinhole
    EXPECT_NEAR(length(at_centre.dir - centre.dir), 0.0f, 1e-6f);
  }
  d.aperture = -1.0f;
  EXPECT_THROW(Camera(d, 4, 4), Error);
}

TEST(PixelSample, StratifiedSamplesCoverEveryStratum) {
  for (int m : {2, 3, 4}) {
    std::set<std::pair<int, int>> cells;
    for (int s = 0; s < m * m; ++s) {
      const Vec2f p = pixel_sample(99, 12345, s, m * m);
      ASSERT_GE(p.x, 0.0f);
      ASSERT_LT(p.x, 1.0f);
      ASSERT_GE(p.y, 0.0f);
      ASSERT_LT(p.y, 1.0f);
      cells.insert({int(p.x * m), int(p.y * m)});
    }
    EXPECT_EQ(cells.size(), size_t(m * m)) << m << "x" << m;
  }
  EXPECT_EQ(pixel_sample(1, 2, 0, 1).x, 0.5f);  // one sample: the pixel centre, as the lecture notes say
}

TEST(PixelSample, StreamsDependOnSeedPixelAndSample) {
  const Vec2f a = pixel_sample(1, 7, 3, 16);
  EXPECT_EQ(a.x, pixel_sample(1, 7, 3, 16).x);
  EXPECT_NE(a.x, pixel_sample(2, 7, 3, 16).x);
  EXPECT_NE(a.x, pixel_sample(1, 8, 3, 16).x);
}

}  // namespace
}  // namespace rp
