// Camera::generate_rays for the pinhole camera, 8 rays at a time: pinhole_direction on float8
// lanes (the scalar generate's operations, so the same bits), the rays written as records
// through one transpose. Built for AVX2+FMA; Camera::generate_rays calls it only on such a CPU.

#include <limits>

#include "engine/render/camera.h"
#include "simd/float8.h"
#include "simd/lanes8.h"

namespace rp {

void Camera::pinhole_rays8(const float* px, const float* py, size_t n, Ray* out) const {
  using simd::float8;
  static_assert(sizeof(Ray) == 32);
  for (size_t at = 0; at < n; at += 8) {
    const Vec3<float8> d = pinhole_direction<float8>(float8::load_unaligned(px + at), float8::load_unaligned(py + at));
    float8 rows[8] = {float8(eye_.x),
                      float8(eye_.y),
                      float8(eye_.z),
                      float8(0.0f),
                      d.x,
                      d.y,
                      d.z,
                      float8(std::numeric_limits<float>::infinity())};
    simd::transpose8x8(rows);
    for (int i = 0; i < 8; ++i) rows[i].store_unaligned(&out[at + size_t(i)].org.x);
  }
}

}  // namespace rp
