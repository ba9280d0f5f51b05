// Pinhole camera against the seeds' pixel mapping, and the sample pattern.

#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "engine/camera.h"
#include "engine/error.h"
#include "engine/render.h"

namespace rp {
namespace {

TEST(PinholeCamera, RaysFollowTheSeedsPixelMapping) {
  // Camera at the origin looking down -z: u = +x, v = +y, w = -z.
  const CameraDesc d{{0, 0, 0}, {0, 0, -1}, {0, 1, 0}, 60.0f};
  const int nx = 64, ny = 48;
  const PinholeCamera cam(d, nx, ny);
  const double ym = std::tan(60.0 * kPi / 360.0), xm = double(nx) / ny * ym;
  for (int i : {0, 17, 63})
    for (int row : {0, 20, 47}) {
      const int j = ny - 1 - row;  // the seeds count j from the bottom
      const double x = ((i + 0.5) / nx * 2 - 1) * xm, y = ((j + 0.5) / ny * 2 - 1) * ym;
      const Vec3d want = normalize(Vec3d{x, y, -1.0});
      const Ray r = cam.generate(i + 0.5f, row + 0.5f);
      EXPECT_EQ(r.org, (Vec3f{0, 0, 0}));
      EXPECT_NEAR(r.dir.x, want.x, 1e-6);
      EXPECT_NEAR(r.dir.y, want.y, 1e-6);
      EXPECT_NEAR(r.dir.z, want.z, 1e-6);
    }
}

TEST(PinholeCamera, CentreRayLooksAtTheTarget) {
  const CameraDesc d{{1, 2, 3}, {4, 6, 3}, {0, 0, 1}, 45.0f};
  const PinholeCamera cam(d, 10, 10);
  const Ray r = cam.generate(5.0f, 5.0f);
  EXPECT_NEAR(r.dir.x, 0.6f, 1e-6);
  EXPECT_NEAR(r.dir.y, 0.8f, 1e-6);
  EXPECT_NEAR(r.dir.z, 0.0f, 1e-6);
}

TEST(PinholeCamera, DegeneratePlacementsAreErrors) {
  EXPECT_THROW(PinholeCamera(CameraDesc{{0, 0, 0}, {0, 0, 0}, {0, 1, 0}, 45}, 4, 4), Error);
  EXPECT_THROW(PinholeCamera(CameraDesc{{0, 0, 0}, {0, 1, 0}, {0, 1, 0}, 45}, 4, 4), Error);
  EXPECT_THROW(PinholeCamera(CameraDesc{{0, 0, 0}, {0, 0, 1}, {0, 1, 0}, 180}, 4, 4), Error);
  EXPECT_THROW(PinholeCamera(CameraDesc{{0, 0, 0}, {0, 0, 1}, {0, 1, 0}, 45}, 0, 4), Error);
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
  EXPECT_EQ(pixel_sample(1, 2, 0, 1).x, 0.5f);  // one sample: the pixel centre, as the seeds say
}

TEST(PixelSample, StreamsDependOnSeedPixelAndSample) {
  const Vec2f a = pixel_sample(1, 7, 3, 16);
  EXPECT_EQ(a.x, pixel_sample(1, 7, 3, 16).x);
  EXPECT_NE(a.x, pixel_sample(2, 7, 3, 16).x);
  EXPECT_NE(a.x, pixel_sample(1, 8, 3, 16).x);
}

}  // namespace
}  // namespace rp
