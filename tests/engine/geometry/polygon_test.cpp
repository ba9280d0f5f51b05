// Polygons: star and tiling inside tests, convex against even-odd, convexity, the Newell
// normal.

#include <gtest/gtest.h>

#include "tests/support/geometry.h"

namespace rp {
namespace {

using namespace rp::test;

/// Regular star: 10 vertices alternating outer radius 2 (even index, the first at angle 0)
/// and inner radius 0.8, counter-clockwise, mapped into 3D by `place`.
template <typename F>
std::vector<Vec3d> star(F place) {
  std::vector<Vec3d> v;
  for (int i = 0; i < 10; ++i) {
    const double a = kPi / 5 * i, rad = i % 2 == 0 ? 2.0 : 0.8;
    v.push_back(place(rad * std::cos(a), rad * std::sin(a)));
  }
  return v;
}

/// Crossing count with closed y-ranges: a test ray through a vertex counts both its edges.
int naive_crossings(const std::vector<Vec3d>& v, int ax, int ay, double px, double py) {
  int n = 0;
  for (size_t i = 0, j = v.size() - 1; i < v.size(); j = i++) {
    const double xi = v[i][ax], yi = v[i][ay], xj = v[j][ax], yj = v[j][ay];
    if (yi == yj || py < std::min(yi, yj) || py > std::max(yi, yj)) continue;
    if (px < (xj - xi) * (py - yi) / (yj - yi) + xi) ++n;
  }
  return n;
}

struct PlanarFrame {
  const char* name;
  std::function<Vec3d(double, double)> place;  // 2D -> 3D point on the polygon's plane
  std::function<Rayd(double, double)> ray_at;  // ray hitting the plane at that 2D point, t = 5
};

std::vector<PlanarFrame> planar_frames() {
  return {{"z=0", [](double x, double y) { return Vec3d{x, y, 0}; },
           [](double x, double y) { return make_ray<double>({x, y, 5}, {0, 0, -1}); }},
          {"x=0", [](double x, double y) { return Vec3d{0, x, y}; },
           [](double x, double y) { return make_ray<double>({5, x, y}, {-1, 0, 0}); }}};
}

TEST(PolygonStar, KnownInsideAndOutsidePoints) {
  for (const PlanarFrame& fr : planar_frames()) {
    const std::vector<Vec3d> v = star(fr.place);
    const PolygonPlane<double> plane = polygon_plane(as_span(v));
    EXPECT_FALSE(polygon_is_convex(as_span(v)));
    const auto at_angle = [](double deg, double rad) {
      const double a = deg * kPi / 180;
      return std::array<double, 2>{rad * std::cos(a), rad * std::sin(a)};
    };
    // Inside: center, inner pentagon, every tip. Outside: notches, far away.
    for (const auto& p : {std::array<double, 2>{0.1, 0.05}, at_angle(36, 0.5), at_angle(180, 0.5),
                          at_angle(72, 1.9), at_angle(144, 1.5), at_angle(216, 1.2),
                          at_angle(288, 1.7), at_angle(0.5, 1.9)}) {
      const Intersection<double> h = intersect_polygon_even_odd(fr.ray_at(p[0], p[1]), v, plane);
      ASSERT_TRUE(h.hit) << fr.name << " " << p[0] << "," << p[1];
      EXPECT_EQ(h.t, 5.0);
      EXPECT_TRUE(intersect_polygon(fr.ray_at(p[0], p[1]), v, plane, false).hit);
    }
    for (const auto& p : {at_angle(36, 1.0), at_angle(108, 1.2), at_angle(180, 1.5),
                          at_angle(252, 0.9), at_angle(324, 1.9), std::array<double, 2>{3, 3},
                          at_angle(0, 2.5), std::array<double, 2>{-2, 0}}) {
      EXPECT_FALSE(intersect_polygon_even_odd(fr.ray_at(p[0], p[1]), v, plane).hit)
          << fr.name << " " << p[0] << "," << p[1];
    }
  }
}

TEST(PolygonStar, TestRayThroughAVertexCountsItOnce) {
  for (const PlanarFrame& fr : planar_frames()) {
    const std::vector<Vec3d> v = star(fr.place);
    const PolygonPlane<double> plane = polygon_plane(as_span(v));
    const ProjectionAxes pa = projection_axes(plane.drop_axis);
    // The scan line y = 0 passes through the tip (2, 0), where the boundary crosses it.
    // Naive closed counting sees both edges there and calls the center outside.
    for (double px : {0.0, -0.5, 1.0}) {
      EXPECT_EQ(naive_crossings(v, pa.x, pa.y, px, 0.0) % 2, 0) << "naive count is even";
      EXPECT_TRUE(intersect_polygon_even_odd(fr.ray_at(px, 0.0), v, plane).hit)
          << fr.name << " px " << px;
    }
    // Through the inner vertex at 180 degrees and the tip at 0: outside in the notch.
    EXPECT_FALSE(intersect_polygon_even_odd(fr.ray_at(-1.5, 0.0), v, plane).hit) << fr.name;
    // A local extremum: the scan line through the tip at 72 degrees only touches it.
    const double tip_y = 2 * std::sin(2 * kPi / 5);
    const double tip_x = 2 * std::cos(2 * kPi / 5);
    EXPECT_EQ(v[2][pa.y], tip_y);
    EXPECT_FALSE(intersect_polygon_even_odd(fr.ray_at(tip_x - 1, tip_y), v, plane).hit);
    // The right-most tip itself lies on the boundary; the half-open rule with a +x test ray
    // puts it outside.
    const Intersection<double> at_tip = intersect_polygon_even_odd(fr.ray_at(2.0, 0.0), v, plane);
    EXPECT_FALSE(at_tip.hit);
  }
}

// Three polygons (one non-convex) tiling the square [-2, 2]^2 and sharing the vertex (0, 0)
// and the edges from it: each shared point is inside exactly one polygon.
TEST(PolygonTiling, SharedVertexAndEdgesAreInsideExactlyOnePolygon) {
  for (const PlanarFrame& fr : planar_frames()) {
    const auto poly = [&](std::initializer_list<std::array<double, 2>> pts) {
      std::vector<Vec3d> v;
      for (const auto& p : pts) v.push_back(fr.place(p[0], p[1]));
      return v;
    };
    const std::vector<std::vector<Vec3d>> tiles = {
        poly({{-2, -2}, {2, -2}, {2, 0}, {0, 0}, {0, 2}, {-2, 2}}),  // L shape, reflex at 0
        poly({{0, 0}, {2, 0}, {2, 2}}),
        poly({{0, 0}, {2, 2}, {0, 2}})};
    EXPECT_FALSE(polygon_is_convex(as_span(tiles[0])));
    std::vector<std::array<double, 2>> shared = {{0, 0}};
    for (double s : {0.25, 0.5, 1.0, 1.5, 1.75}) {
      shared.push_back({s, 0});
      shared.push_back({0, s});
      shared.push_back({s, s});
    }
    for (const auto& p : shared) {
      int inside = 0;
      for (const auto& tile : tiles) {
        inside += intersect_polygon_even_odd(fr.ray_at(p[0], p[1]), tile,
                                             polygon_plane(as_span(tile)))
                      .hit;
      }
      EXPECT_EQ(inside, 1) << fr.name << " at " << p[0] << "," << p[1];
    }
  }
}

TEST(PolygonProperty, ConvexTestEqualsEvenOddOnConvexPolygons) {
  std::mt19937 rng(606);
  int checked = 0, hits = 0;
  for (int i = 0; i < 20000; ++i) {
    // Convex polygon on an ellipse in a random plane; angles at least 0.05 rad apart.
    const int count = 3 + int(rng() % 8);
    std::vector<double> angles;
    while (int(angles.size()) < count) {
      const double a = uniform(rng, 0.0, 2 * kPi);
      bool ok = true;
      for (double b : angles) {
        const double gap = std::abs(a - b);
        ok &= std::min(gap, 2 * kPi - gap) > 0.05;
      }
      if (ok) angles.push_back(a);
    }
    std::sort(angles.begin(), angles.end());
    if (rng() % 2) std::reverse(angles.begin(), angles.end());  // clockwise too
    const double ea = uniform(rng, 0.5, 3.0), eb = uniform(rng, 0.5, 3.0);
    const Vec3d center = uniform_vec(rng, -3.0, 3.0);
    const Vec3d normal = unit_vec<double>(rng);
    const Basis<double> basis = orthonormal_basis(normal);
    std::vector<std::array<double, 2>> local;
    std::vector<Vec3d> v;
    for (double a : angles) {
      local.push_back({ea * std::cos(a), eb * std::sin(a)});
      v.push_back(center + basis.t * local.back()[0] + basis.b * local.back()[1]);
    }
    EXPECT_TRUE(polygon_is_convex(as_span(v)));
    const PolygonPlane<double> plane = polygon_plane(as_span(v));
    // Aim point in the polygon's plane, within 1.2x its ellipse box.
    const double px = uniform(rng, -1.2, 1.2) * ea, py = uniform(rng, -1.2, 1.2) * eb;
    const Vec3d target = center + basis.t * px + basis.b * py;
    const Vec3d o = uniform_vec(rng, -8.0, 8.0);
    RayT<double> r = make_ray(o, (target - o) * uniform(rng, 0.5, 2.0));
    if (std::abs(dot(normalize(r.dir), normal)) < 1e-3) continue;
    // Truth in 2D; skip aim points within 1e-7 of an edge line.
    bool pos = false, neg = false, near_edge = false;
    for (int k = 0; k < count; ++k) {
      const auto& a = local[k];
      const auto& b = local[(k + 1) % count];
      const double ex = b[0] - a[0], ey = b[1] - a[1];
      const double s = (ex * (py - a[1]) - ey * (px - a[0])) / std::hypot(ex, ey);
      near_edge |= std::abs(s) < 1e-7;
      pos |= s > 0;
      neg |= s < 0;
    }
    if (near_edge) continue;
    const bool truth = !(pos && neg);
    ++checked;
    hits += truth;
    const Intersection<double> hc = intersect_polygon_convex(r, v, plane);
    const Intersection<double> he = intersect_polygon_even_odd(r, v, plane);
    ASSERT_EQ(hc.hit, truth) << "case " << i;
    ASSERT_EQ(he.hit, truth) << "case " << i;
    EXPECT_EQ(hc.t, he.t);
    EXPECT_EQ(intersect_polygon(r, v, plane, true).hit, truth);
    EXPECT_EQ(intersect_polygon(r, v, plane, false).hit, truth);
    if (truth) {
      const Vec3d p = r.at(hc.t);
      EXPECT_LE(std::abs(dot(plane.n, p) + plane.d) / length(plane.n), 1e-9 * (length(p) + 1));
    }
  }
  EXPECT_GE(checked, 10000);
  EXPECT_GE(hits, 3000);
}

TEST(PolygonProperty, ConvexTestIgnoresTheSignOfThePlaneNormal) {
  const std::vector<Vec3d> sq = {{-1, -1, 2}, {1, -1, 2}, {1, 1, 2}, {-1, 1, 2}};
  const PolygonPlane<double> plane = polygon_plane(as_span(sq));
  const PolygonPlane<double> flipped{-plane.n, -plane.d, plane.drop_axis};
  for (const PolygonPlane<double>& p : {plane, flipped}) {
    const Intersection<double> in = intersect_polygon_convex(
        make_ray<double>({0.5, -0.25, 0}, {0, 0, 1}), sq, p);
    ASSERT_TRUE(in.hit);
    EXPECT_EQ(in.t, 2.0);
    EXPECT_FALSE(intersect_polygon_convex(make_ray<double>({1.5, 0, 0}, {0, 0, 1}), sq, p).hit);
    EXPECT_TRUE(intersect_polygon_convex(make_ray<double>({1, 1, 0}, {0, 0, 1}), sq, p).hit);
    EXPECT_TRUE(intersect_polygon_convex(make_ray<double>({1, 0, 0}, {0, 0, 1}), sq, p).hit);
    EXPECT_TRUE(intersect_polygon_even_odd(make_ray<double>({0.5, -0.25, 0}, {0, 0, 1}), sq, p)
                    .hit);
  }
}

TEST(PolygonConvexity, DetectsConvexNonConvexAndPentagram) {
  const auto z0 = [](std::initializer_list<std::array<double, 2>> pts) {
    std::vector<Vec3d> v;
    for (const auto& p : pts) v.push_back({p[0], p[1], 0});
    return v;
  };
  EXPECT_TRUE(polygon_is_convex(as_span(z0({{0, 0}, {1, 0}, {0, 1}}))));
  EXPECT_TRUE(polygon_is_convex(as_span(z0({{0, 0}, {1, 0}, {1, 1}, {0, 1}}))));
  EXPECT_TRUE(polygon_is_convex(as_span(z0({{0, 1}, {1, 1}, {1, 0}, {0, 0}}))));  // clockwise
  EXPECT_TRUE(polygon_is_convex(as_span(z0({{0, 0}, {1, 0}, {2, 0}, {2, 2}, {0, 2}}))));
  EXPECT_FALSE(polygon_is_convex(as_span(z0({{0, 0}, {2, 0}, {1, 0.5}, {2, 2}, {0, 2}}))));
  std::vector<Vec3d> pentagram;
  for (int i = 0; i < 5; ++i) {
    const double a = 2 * kPi / 5 * ((2 * i) % 5);
    pentagram.push_back({std::cos(a), std::sin(a), 0});
  }
  EXPECT_FALSE(polygon_is_convex(as_span(pentagram)));
  EXPECT_FALSE(polygon_is_convex(as_span(z0({{0, 0}, {1, 1}, {2, 2}}))));  // degenerate
  EXPECT_FALSE(polygon_is_convex(as_span(z0({{0, 0}, {1, 1}}))));
  EXPECT_FALSE(polygon_is_convex(as_span(z0({{0, 0}, {1, 0}, {0, kNanT<double>}}))));
}

TEST(PolygonPlane, NewellNormalIsTwiceTheAreaAndDropsTheDominantAxis) {
  const std::vector<Vec3d> sq = {{0, 0, 3}, {2, 0, 3}, {2, 2, 3}, {0, 2, 3}};
  const PolygonPlane<double> p = polygon_plane(as_span(sq));
  EXPECT_EQ(p.n, (Vec3d{0, 0, 8}));
  EXPECT_EQ(p.d, -24.0);
  EXPECT_EQ(p.drop_axis, 2);
  const std::vector<Vec3d> side = {{1, 0, 0}, {1, 0, 1}, {1, 1, 1}, {1, 1, 0}};
  const PolygonPlane<double> q = polygon_plane(as_span(side));
  EXPECT_EQ(q.drop_axis, 0);
  EXPECT_EQ(q.n, (Vec3d{-2, 0, 0}));  // clockwise in (y, z): -x
  EXPECT_EQ(q.d, 2.0);
  const ProjectionAxes pa = projection_axes(1);
  EXPECT_EQ(pa.x, 2);
  EXPECT_EQ(pa.y, 0);
  // Too few vertices: zero normal, every ray misses.
  const std::vector<Vec3d> two = {{0, 0, 0}, {1, 0, 0}};
  EXPECT_EQ(polygon_plane(as_span(two)).n, Vec3d(0.0));
  EXPECT_FALSE(intersect_polygon_convex(make_ray<double>({0, 0, 1}, {0, 0, -1}), two,
                                        polygon_plane(as_span(two)))
                   .hit);
}

}  // namespace
}  // namespace rp
