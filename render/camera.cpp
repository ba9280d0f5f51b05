#include "render/camera.h"

#include <algorithm>
#include <cmath>

#include "base/error.h"
#include "render/camera_lanes.h"

namespace rp {

void check_image_size(const std::string& what, int64_t width, int64_t height) {
  RP_CHECK(width >= 1 && height >= 1 && width <= kMaxImageEdge && height <= kMaxImageEdge &&
               width * height <= kMaxImagePixels,
           what, ": ", width, "x", height, " is out of range (each side 1..", kMaxImageEdge, ", at most ",
           kMaxImagePixels, " pixels)");
}

Camera::Camera(const CameraDesc& d, int width, int height) : model_(d.model), width_(width), height_(height) {
  check_image_size("camera: resolution", width, height);
  RP_CHECK(d.vfov_degrees > 0.0f && d.vfov_degrees < 180.0f, "camera: vertical fov ", d.vfov_degrees,
           " degrees must be in (0, 180)");
  RP_CHECK(is_finite(d.eye) && is_finite(d.look_at) && is_finite(d.up), "camera: non-finite eye, look-at or up");
  // The rays start at the eye (or on the lens around it): they must be valid rays (core/ray.h).
  RP_CHECK(in_coordinate_range(d.eye), "camera: eye (", d.eye.x, ", ", d.eye.y, ", ", d.eye.z,
           ") is outside the supported coordinate range |x| <= 1073741824 (2^30)");
  RP_CHECK(in_coordinate_range(d.look_at), "camera: look-at (", d.look_at.x, ", ", d.look_at.y, ", ", d.look_at.z,
           ") is outside the supported coordinate range |x| <= 1073741824 (2^30)");
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
  if (model_ == CameraModel::fisheye) {
    RP_CHECK(d.fisheye_fov_degrees > 0.0f && d.fisheye_fov_degrees <= 360.0f, "camera: fisheye fov ",
             d.fisheye_fov_degrees, " degrees must be in (0, 360]");
    fisheye_half_ = d.fisheye_fov_degrees * float(kPi) / 360.0f;
  }
  if (model_ == CameraModel::thin_lens) {
    RP_CHECK(d.aperture >= 0.0f && std::isfinite(d.aperture), "camera: aperture ", d.aperture, " must be >= 0");
    RP_CHECK(in_coordinate_range(abs(d.eye) + Vec3f(d.aperture)), "camera: aperture ", d.aperture,
             " puts the lens outside the supported coordinate range |x| <= 1073741824 (2^30)");
    RP_CHECK(d.focus_distance >= 0.0f && d.focus_distance <= kMaxDirection, "camera: focus distance ",
             d.focus_distance, " must be in [0, 2147483648]");
    aperture_ = d.aperture;
    focus_ = d.focus_distance > 0.0f ? d.focus_distance : length(view);
  }
}

Ray Camera::generate(float px, float py, Vec2f lens) const {
  Ray r;
  ray_lanes<float>(px, py, lens.x, lens.y, r.org, r.tnear, r.dir, r.tfar);
  return r;
}

void Camera::generate_rays(std::span<const float> px, std::span<const float> py, const Vec2f* lens,
                           std::span<Ray> out) const {
  static const bool avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  size_t i = 0;
  if (avx2) {
    i = px.size() - px.size() % 8;
    rays8(px.data(), py.data(), lens, i, out.data());
  }
  for (; i < px.size(); ++i) out[i] = generate(px[i], py[i], lens ? lens[i] : Vec2f{0.5f, 0.5f});
}

std::optional<Vec2f> Camera::project(const Vec3f& direction) const {
  const Vec3f d = normalize(direction);
  const float dw = dot(d, w_), du = dot(d, u_), dv = dot(d, v_);
  float sx = 0.0f, sy = 0.0f;
  switch (model_) {
    case CameraModel::pinhole:
    case CameraModel::thin_lens:
      if (!(dw > 0.0f)) return std::nullopt;
      sx = du / dw / xm_;
      sy = dv / dw / ym_;
      if (std::abs(sx) > 1.0f || std::abs(sy) > 1.0f) return std::nullopt;
      break;
    case CameraModel::panoramic: {
      const float horizontal = std::sqrt(dw * dw + du * du);
      if (!(horizontal > 0.0f)) return std::nullopt;
      sx = std::atan2(du, dw) / float(kPi);
      sy = dv / horizontal / ym_;
      if (std::abs(sy) > 1.0f) return std::nullopt;
      break;
    }
    case CameraModel::fisheye: {
      const float theta = std::atan2(std::sqrt(du * du + dv * dv), dw);
      const float r = theta / fisheye_half_;
      if (r > 1.0f) return std::nullopt;
      const float psi = std::atan2(dv, du), circle = 0.5f * float(std::min(width_, height_));
      return Vec2f{0.5f * float(width_) + r * std::cos(psi) * circle, 0.5f * float(height_) - r * std::sin(psi) * circle};
    }
  }
  return Vec2f{(sx + 1.0f) * 0.5f * float(width_), (1.0f - sy) * 0.5f * float(height_)};
}

CameraDesc frame_bounds(const Box3f& bounds, int up_axis, float vfov_degrees) {
  CameraDesc c;
  c.vfov_degrees = vfov_degrees;
  const UpFrame f = up_frame(up_axis);
  c.up = f.up;
  if (bounds.empty()) {
    c.eye = f.front * 5.0f;
    return c;
  }
  const Vec3f centre = bounds.center();
  const float radius = std::max(0.5f * length(bounds.extent()), 1e-6f);
  const float dist = radius / std::sin(vfov_degrees * float(kPi) / 360.0f) * 1.05f;
  c.look_at = centre;
  c.eye = centre + normalize(f.up * 0.35f + f.front) * dist;
  // A scene filling the coordinate range is seen from its edge (the eye must be in range).
  for (int a = 0; a < 3; ++a) c.eye[a] = std::clamp(c.eye[a], -kMaxCoordinate, kMaxCoordinate);
  if (c.eye == c.look_at) {  // the whole range filled: the eye to the far side along the front axis
    const int a = max_abs_axis(f.front);
    c.eye[a] = c.look_at[a] > 0.0f ? -kMaxCoordinate : kMaxCoordinate;
  }
  return c;
}

}  // namespace rp
