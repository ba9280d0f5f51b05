#include "core/queries.h"

#include <array>

#include "base/error.h"
#include "core/backend.h"

namespace rp {

void inside(const Backend& backend, std::span<const Vec3f> points, std::span<uint8_t> out) {
  RP_CHECK(out.size() == points.size(), "inside: ", out.size(), " answers for ", points.size(), " points");
  for_each_chunk(points.size(), [&](size_t begin, size_t n) {
    std::vector<Ray> rays(3 * n);
    for (size_t i = 0; i < n; ++i)
      for (size_t k = 0; k < 3; ++k) rays[3 * i + k] = Ray{points[begin + i], 0.0f, kInsideDirections[k]};
    std::vector<uint32_t> counts(rays.size());
    backend.count_hits(rays, counts);
    for (size_t i = 0; i < n; ++i) {
      const uint32_t odd = (counts[3 * i] & 1u) + (counts[3 * i + 1] & 1u) + (counts[3 * i + 2] & 1u);
      out[begin + i] = uint8_t(odd >= 2 && in_coordinate_range(points[begin + i]));
    }
  });
}

void signed_distance(const Backend& backend, std::span<const Vec3f> points, std::span<float> out) {
  RP_CHECK(out.size() == points.size(), "signed_distance: ", out.size(), " answers for ", points.size(), " points");
  std::vector<uint8_t> in(points.size());
  inside(backend, points, in);
  for_each_chunk(points.size(), [&](size_t begin, size_t n) {
    std::vector<PointQuery> q(n);
    for (size_t i = 0; i < n; ++i) q[i].point = points[begin + i];
    std::vector<ClosestPoint> c(n);
    backend.closest_points(q, c);
    for (size_t i = 0; i < n; ++i) {
      const bool valid = in_coordinate_range(points[begin + i]);
      out[begin + i] = !valid          ? std::numeric_limits<float>::quiet_NaN()
                       : in[begin + i] ? -c[i].distance
                                       : c[i].distance;
    }
  });
}

}  // namespace rp
