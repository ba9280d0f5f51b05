#pragma once
/// Cameras that turn image positions into primary rays.

#include "engine/ray.h"
#include "engine/scene.h"

namespace rp {

/// Pinhole camera with the seeds' pixel mapping (lecture "Ray Tracing Basics", eye rays):
/// camera frame w = normalize(look_at - eye), u = normalize(w x up), v = u x w; for pixel
/// (i, j) with j counted from the bottom row,
///   x = ((i + 0.5) / nx * 2 - 1) * aspect * tan(fov / 2),  y = ((j + 0.5) / ny * 2 - 1) * tan(fov / 2),
///   d = normalize(w + x u + y v), origin = eye.
class PinholeCamera {
 public:
  /// Throws rp::Error for a degenerate placement (eye == look_at, up parallel to the view
  /// direction) or a field of view outside (0, 180) degrees.
  PinholeCamera(const CameraDesc& desc, int width, int height);

  /// Ray through image position (px, py) in pixels: (0, 0) is the top-left corner of the
  /// image, pixel (i, r) in row r from the top has its centre at (i + 0.5, r + 0.5).
  /// The direction is unit length; tnear = 0, tfar = +inf.
  Ray generate(float px, float py) const {
    const float x = (px / float(width_) * 2.0f - 1.0f) * xm_;
    const float y = (1.0f - py / float(height_) * 2.0f) * ym_;
    return {eye_, 0.0f, normalize(w_ + u_ * x + v_ * y), std::numeric_limits<float>::infinity()};
  }

  int width() const { return width_; }
  int height() const { return height_; }

 private:
  Vec3f eye_, u_, v_, w_;
  float xm_, ym_;  ///< half extents of the image window at distance 1: aspect*tan(fov/2), tan(fov/2)
  int width_, height_;
};

/// A camera that frames `bounds` from the front-above (+z, +y) with the given fov, used
/// when a scene has none.
CameraDesc frame_bounds(const Box3f& bounds, float vfov_degrees = 40.0f);

}  // namespace rp
