// Camera::generate_rays 8 rays at a time, for every model: Camera::ray_lanes on float8 lanes
// (generate's operations, so the same bits), the rays written as records through one
// transpose. Built for AVX2+FMA; Camera::generate_rays calls it only on such a CPU.

#include <limits>

#include "render/camera.h"
#include "render/camera_lanes.h"
#include "simd/float8.h"
#include "simd/lanes8.h"

namespace rp {

void Camera::rays8(const float* px, const float* py, const Vec2f* lens, size_t n, Ray* out) const {
  using simd::float8;
  static_assert(sizeof(Ray) == 32 && sizeof(Vec2f) == 8);
  for (size_t at = 0; at < n; at += 8) {
    float8 lx(0.5f), ly(0.5f);
    if (lens) simd::load_pairs8(&lens[at].x, lx, ly);
    Vec3<float8> org, dir;
    float8 tnear, tfar;
    ray_lanes<float8>(float8::load_unaligned(px + at), float8::load_unaligned(py + at), lx, ly, org, tnear, dir, tfar);
    float8 rows[8] = {org.x, org.y, org.z, tnear, dir.x, dir.y, dir.z, tfar};
    simd::transpose8x8(rows);
    for (int i = 0; i < 8; ++i) rows[i].store_unaligned(&out[at + size_t(i)].org.x);
  }
}

}  // namespace rp
