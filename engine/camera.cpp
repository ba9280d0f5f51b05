#include "engine/camera.h"

#include <cmath>

#include "engine/error.h"

namespace rp {

PinholeCamera::PinholeCamera(const CameraDesc& d, int width, int height) : width_(width), height_(height) {
  RP_CHECK(width > 0 && height > 0, "camera: resolution ", width, "x", height, " must be positive");
  RP_CHECK(d.vfov_degrees > 0.0f && d.vfov_degrees < 180.0f, "camera: vertical fov ", d.vfov_degrees,
           " degrees must be in (0, 180)");
  RP_CHECK(is_finite(d.eye) && is_finite(d.look_at) && is_finite(d.up), "camera: non-finite eye, look-at or up");
  const Vec3f view = d.look_at - d.eye;
  RP_CHECK(length(view) > 0.0f, "camera: eye and look-at coincide");
  w_ = normalize(view);
  const Vec3f side = cross(w_, d.up);
  RP_CHECK(length(side) > 1e-6f * length(d.up), "camera: up vector is parallel to the view direction");
  u_ = normalize(side);
  v_ = cross(u_, w_);
  eye_ = d.eye;
  ym_ = std::tan(d.vfov_degrees * float(kPi) / 360.0f);
  xm_ = float(width) / float(height) * ym_;
}

CameraDesc frame_bounds(const Box3f& bounds, float vfov_degrees) {
  CameraDesc c;
  c.vfov_degrees = vfov_degrees;
  if (bounds.empty()) return c;
  const Vec3f centre = bounds.center();
  const float radius = std::max(0.5f * length(bounds.extent()), 1e-6f);
  const float dist = radius / std::sin(vfov_degrees * float(kPi) / 360.0f) * 1.05f;
  c.look_at = centre;
  c.eye = centre + normalize(Vec3f{0.0f, 0.35f, 1.0f}) * dist;
  return c;
}

}  // namespace rp
