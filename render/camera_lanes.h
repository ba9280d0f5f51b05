#pragma once
// Camera's rays in lanes (base/lanes.h): the operations of Camera::generate written once over
// a lane type F, float for one ray (camera.cpp) and float8 for eight (camera8.cpp), branches
// taken as selects, so the two give the same bits. Inside the library only: the installed
// camera.h declares these members without the lane arithmetic they need.

#include <algorithm>
#include <limits>
#include <utility>

#include "base/lanes.h"
#include "base/trig.h"
#include "render/camera.h"

namespace rp {

/// Image position (px, py) as screen coordinates in [-1, 1], y up.
template <class F>
std::pair<F, F> Camera::screen(const F& px, const F& py) const {
  return {px / F(float(width_)) * F(2.0f) - F(1.0f), F(1.0f) - py / F(float(height_)) * F(2.0f)};
}

/// The pinhole direction through image position (px, py).
template <class F>
Vec3<F> Camera::pinhole_direction(const F& px, const F& py) const {
  const auto [sx, sy] = screen(px, py);
  const Vec3<F> w(F(w_.x), F(w_.y), F(w_.z)), u(F(u_.x), F(u_.y), F(u_.z)), v(F(v_.x), F(v_.y), F(v_.z));
  return unit(w + u * (sx * F(xm_)) + v * (sy * F(ym_)));
}

/// The ray through image positions (px, py), with lens positions (lx, ly) for the thin lens.
template <class F>
void Camera::ray_lanes(const F& px, const F& py, const F& lx, const F& ly, Vec3<F>& org, F& tnear, Vec3<F>& dir,
                       F& tfar) const {
  using L = Lanes<F>;
  const Vec3<F> eye(F(eye_.x), F(eye_.y), F(eye_.z)), w(F(w_.x), F(w_.y), F(w_.z));
  const Vec3<F> u(F(u_.x), F(u_.y), F(u_.z)), v(F(v_.x), F(v_.y), F(v_.z));
  org = eye;
  tnear = F(0.0f);
  tfar = F(std::numeric_limits<float>::infinity());
  switch (model_) {
    case CameraModel::pinhole:
      dir = pinhole_direction<F>(px, py);
      return;
    case CameraModel::panoramic: {
      const auto [sx, sy] = screen(px, py);
      F s, c;
      sincos_lanes(sx * F(float(kPi)), s, c);
      dir = unit(w * c + u * s + v * (sy * F(ym_)));
      return;
    }
    case CameraModel::fisheye: {
      const F circle(0.5f * float(std::min(width_, height_)));
      const F x = (px - F(0.5f * float(width_))) / circle, y = (F(0.5f * float(height_)) - py) / circle;
      const F r = L::sqrt(x * x + y * y);
      F st, ct, sp, cp;
      sincos_lanes(r * F(fisheye_half_), st, ct);
      sincos_lanes(atan2_lanes(y, x), sp, cp);
      const auto outside = r > F(1.0f);  // outside the image circle: no ray (tnear 1 > tfar 0)
      dir = select<F>(outside, w, unit(w * ct + (u * cp + v * sp) * st));
      tnear = L::select(outside, F(1.0f), tnear);
      tfar = L::select(outside, F(0.0f), tfar);
      return;
    }
    case CameraModel::thin_lens: {
      dir = pinhole_direction<F>(px, py);
      if (aperture_ == 0.0f) return;
      const Vec3<F> focus_point = eye + dir * (F(focus_) / dot(dir, w));
      // Concentric square-to-disk mapping (Shirley and Chiu 1997).
      const F a = F(2.0f) * lx - F(1.0f), b = F(2.0f) * ly - F(1.0f);
      const auto centre = a == F(0.0f) && b == F(0.0f), wide = L::abs(a) > L::abs(b);
      const F r = L::select(centre, F(0.0f), L::select(wide, a, b));
      const F t = L::select(
          centre, F(0.0f),
          L::select(wide, F(float(kPi) / 4.0f) * (b / a), F(float(kPi) / 2.0f) - F(float(kPi) / 4.0f) * (a / b)));
      F s, c;
      sincos_lanes(t, s, c);
      org = eye + (u * c + v * s) * (r * F(aperture_));
      dir = unit(focus_point - org);
      return;
    }
  }
}

}  // namespace rp
