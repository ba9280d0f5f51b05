// Camera::generate8 for the pinhole camera, 8 rays at a time: pinhole_direction on float8
// lanes (the scalar generate's operations, so the same bits), the rays written as records
// through one transpose. Built for AVX2+FMA; Camera::generate8 calls it only on such a CPU.

#include <limits>

#include "engine/render/camera.h"
#include "simd/float8.h"
#include "simd/lanes8.h"

namespace rp {

void Camera::generate8_pinhole(const float px[8], const float py[8], Ray out[8]) const {
  using simd::float8;
  static_assert(sizeof(Ray) == 32);
  const Vec3<float8> d = pinhole_direction<float8>(float8::load_unaligned(px), float8::load_unaligned(py));
  float8 rows[8] = {float8(eye_.x), float8(eye_.y), float8(eye_.z), float8(0.0f),
                    d.x, d.y, d.z, float8(std::numeric_limits<float>::infinity())};
  simd::transpose8x8(rows);
  for (int i = 0; i < 8; ++i) rows[i].store_unaligned(&out[i].org.x);
}

}  // namespace rp
