#pragma once
/// Cameras that turn image positions into primary rays: the lecture notes' pinhole, a cylindrical
/// panorama, an equidistant fisheye and a thin lens for depth of field.

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <utility>

#include "core/ray.h"
#include "core/scene.h"

namespace rp {

/// All four models share the camera frame of the lecture notes (lecture "Ray Tracing Basics", eye
/// rays): w = normalize(look_at - eye), u = normalize(w x up), v = u x w.
///
/// - pinhole: for pixel (i, j), j counted from the bottom row,
///   x = ((i + 0.5) / nx * 2 - 1) * aspect * tan(fov / 2), y = ((j + 0.5) / ny * 2 - 1) * tan(fov / 2),
///   d = normalize(w + x u + y v), origin = eye.
/// - panoramic (cylindrical, 360 degrees): the image's x covers the angle phi in [-pi, pi)
///   around v (phi = 0 straight ahead, growing towards u); its y is the height on the unit
///   cylinder, y in [-tan(fov/2), tan(fov/2)]: d = normalize(cos(phi) w + sin(phi) u + y v).
/// - fisheye (equidistant): the image circle of diameter min(nx, ny) pixels, centred; a
///   point at radius r (1 at the circle) and angle psi from u sees the direction at angle
///   theta = r * fisheye_fov / 2 from w: d = cos(theta) w + sin(theta) (cos(psi) u + sin(psi) v).
///   Outside the circle there is no ray (an invalid ray, traced as a miss).
/// - thin lens: the pinhole direction d meets the plane in focus (distance f along w) at
///   P = eye + d f / (d . w); the ray starts at a point L of the lens disk (radius
///   `aperture`, concentric mapping of the lens sample) and points at P (Pharr, Jakob,
///   Humphreys, PBRT 4th ed., 5.2.3). aperture 0 is the pinhole.
/// The largest image raypack makes or reads: each side at most kMaxImageEdge pixels and at most
/// kMaxImagePixels in all (2^28: 3 GiB of float RGB), whoever asks (the CLI, Python, an image file).
inline constexpr int kMaxImageEdge = 32768;
inline constexpr int64_t kMaxImagePixels = int64_t(1) << 28;

/// Throws rp::Error "<what>: WxH is out of range (each side 1..32768, at most 268435456 pixels)"
/// unless a width x height image lies within the limits above.
void check_image_size(const std::string& what, int64_t width, int64_t height);

class Camera {
 public:
  /// Throws rp::Error for a size beyond check_image_size, an eye or look-at point outside the coordinate range
  /// (core/ray.h: every ray it makes must be valid), a degenerate placement (eye == look_at, up parallel to the view
  /// direction), a field of view out of range, an aperture that reaches outside the range or a focus distance outside
  /// [0, 2^31].
  Camera(const CameraDesc& desc, int width, int height);

  /// Ray through image position (px, py) in pixels: (0, 0) is the top-left corner, pixel (i,
  /// r) in row r from the top has its centre at (i + 0.5, r + 0.5). `lens` in [0, 1)^2 picks
  /// the point on the lens (thin lens only). Directions are unit length; tnear = 0, tfar = +inf.
  Ray generate(float px, float py, Vec2f lens = {0.5f, 0.5f}) const;

  /// generate() for the image positions (px[i], py[i]) (lens[i] for position i, or none for a
  /// camera that ignores it) into out[i]: the same rays, bit for bit. Made 8 lanes at a time
  /// where the CPU has AVX2 and FMA (camera8.cpp), the last px.size() % 8 and those of other
  /// CPUs ray by ray. The spans have one size.
  void generate_rays(std::span<const float> px, std::span<const float> py, const Vec2f* lens, std::span<Ray> out) const;

  /// The image position whose ray has direction `dir` (pinhole, panoramic, fisheye), or
  /// nothing when no pixel sees it: the inverse of generate(), used to test the mappings.
  std::optional<Vec2f> project(const Vec3f& dir) const;

  int width() const { return width_; }
  int height() const { return height_; }
  CameraModel model() const { return model_; }

 private:
  /// generate_rays on an AVX2+FMA CPU (camera8.cpp): the first n - n % 8 rays, 8 at a time.
  void rays8(const float* px, const float* py, const Vec2f* lens, size_t n, Ray* out) const;

  /// The ray of generate() in lanes: one lane for generate(), eight for rays8. Defined, with
  /// the two below, in render/camera_lanes.h, which only camera.cpp and camera8.cpp include.
  template <class F>
  void ray_lanes(const F& px, const F& py, const F& lx, const F& ly, Vec3<F>& org, F& tnear, Vec3<F>& dir,
                 F& tfar) const;
  template <class F>
  Vec3<F> pinhole_direction(const F& px, const F& py) const;
  template <class F>
  std::pair<F, F> screen(const F& px, const F& py) const;

  Vec3f eye_, u_, v_, w_;
  float xm_, ym_;  ///< half extents of the image window at distance 1: aspect*tan(fov/2), tan(fov/2)
  float fisheye_half_ = 0.0f;  ///< fisheye: half the field of view, radians
  float aperture_ = 0.0f, focus_ = 0.0f;
  CameraModel model_;
  int width_, height_;
};

/// A pinhole camera that frames `bounds` from the front, a little above, with the given fov,
/// used when a scene has none: front and above as up_frame(up_axis) says (Y up: from +z and
/// +y). The eye is kept within the coordinate range (a scene that fills the range is seen
/// from its edge).
CameraDesc frame_bounds(const Box3f& bounds, int up_axis = 1, float vfov_degrees = 40.0f);

}  // namespace rp
