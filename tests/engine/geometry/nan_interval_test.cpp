// Every routine: NaN in a ray or a primitive never hits; hits exactly at tnear or tfar count
// and just outside do not.

#include <gtest/gtest.h>

#include "tests/support/geometry.h"

namespace rp {
namespace {

using namespace rp::test;

template <typename T>
struct RoutineCase {
  std::string name;
  RayT<T> ray;          // hits at t_exact (and for two-root shapes, second root t_second)
  T t_exact, t_second;  // t_second == t_exact when there is a single root
  std::function<Intersection<T>(const RayT<T>&)> run;
};

template <typename T>
std::vector<RoutineCase<T>> routine_cases() {
  std::vector<RoutineCase<T>> cases;
  const T inf = kInfT<T>;
  // Plane z = 2 and a triangle / square in it; the ray from (0.25, 0.25, 0) along +z: t = 2.
  const RayT<T> up = make_ray<T>({0.25, 0.25, 0}, {0, 0, 1});
  cases.push_back({"plane", up, 2, 2, [](const RayT<T>& r) {
                     return intersect_plane(r, Vec3<T>{0, 0, 1}, T(-2));
                   }});
  const Vec3<T> v0{0, 0, 2}, v1{1, 0, 2}, v2{0, 1, 2};
  for (const auto& m : triangle_methods<T>()) {
    cases.push_back({std::string("triangle_") + m.name, up, 2, 2,
                     [=](const RayT<T>& r) { return m.fn(r, v0, v1, v2); }});
  }
  // Sphere center (0, 0, 4) radius 2 from the origin along +z: t = 2 and 6.
  const RayT<T> s_ray = make_ray<T>({0, 0, 0}, {0, 0, 1});
  for (const auto& m : sphere_methods<T>()) {
    cases.push_back({std::string("sphere_") + m.name, s_ray, 2, 6, [=](const RayT<T>& r) {
                       return m.fn(r, Vec3<T>{0, 0, 4}, T(2));
                     }});
  }
  // Cylinder radius 2 along y from (5, 0, 0) along -x: t = 3 and 7.
  const Quadric<T> cyl = Quadric<T>::cylinder({0, 0, 0}, 2, 2, 1);
  cases.push_back({"quadric_cylinder", make_ray<T>({5, 0, 0}, {-1, 0, 0}), 3, 7,
                   [=](const RayT<T>& r) { return intersect_quadric(r, cyl); }});
  // Square polygon in z = 2.
  const std::vector<Vec3<T>> square = {{-1, -1, 2}, {1, -1, 2}, {1, 1, 2}, {-1, 1, 2}};
  const PolygonPlane<T> plane = polygon_plane(std::span<const Vec3<T>>(square));
  cases.push_back({"polygon_convex", up, 2, 2, [=](const RayT<T>& r) {
                     return intersect_polygon_convex(r, square, plane);
                   }});
  cases.push_back({"polygon_even_odd", up, 2, 2, [=](const RayT<T>& r) {
                     return intersect_polygon_even_odd(r, square, plane);
                   }});
  // Box +-2 from (-3, 0, 0) along +x: slab [1, 5]; reported through t_enter.
  const Box3<T> box({-2, -2, -2}, {2, 2, 2});
  cases.push_back({"box", make_ray<T>({-3, 0, 0}, {1, 0, 0}), 1, 1, [=](const RayT<T>& r) {
                     const SlabHit<T> h = intersect_box(r, box);
                     Intersection<T> out;
                     out.hit = h.hit;
                     out.t = h.hit ? h.t_enter : inf;
                     return out;
                   }});
  return cases;
}

template <typename T>
void check_nan_rays_miss() {
  const T nan = kNanT<T>;
  for (const RoutineCase<T>& c : routine_cases<T>()) {
    ASSERT_TRUE(c.run(c.ray).hit) << c.name;
    for (int field = 0; field < 8; ++field) {
      RayT<T> r = c.ray;
      if (field < 3) r.org[field] = nan;
      else if (field < 6) r.dir[field - 3] = nan;
      else if (field == 6) r.tnear = nan;
      else r.tfar = nan;
      const Intersection<T> h = c.run(r);
      EXPECT_FALSE(h.hit) << c.name << " NaN in field " << field;
      EXPECT_FALSE(std::isnan(h.t)) << c.name << " NaN in field " << field;
    }
  }
}

TEST(NanInputs, NanInAnyRayComponentNeverHitsDouble) { check_nan_rays_miss<double>(); }
TEST(NanInputs, NanInAnyRayComponentNeverHitsFloat) { check_nan_rays_miss<float>(); }

TEST(NanInputs, NanInThePrimitiveNeverHits) {
  const double nan = kNanT<double>;
  const Rayd up = make_ray<double>({0.25, 0.25, 0}, {0, 0, 1});
  EXPECT_FALSE(intersect_plane(up, Vec3d{0, nan, 1}, -2.0).hit);
  EXPECT_FALSE(intersect_plane(up, Vec3d{0, 0, 1}, nan).hit);
  for (int k = 0; k < 9; ++k) {
    Vec3d v[3] = {{0, 0, 2}, {1, 0, 2}, {0, 1, 2}};
    v[k / 3][k % 3] = nan;
    for (const auto& m : triangle_methods<double>()) {
      EXPECT_FALSE(m.fn(up, v[0], v[1], v[2]).hit) << m.name << " vertex field " << k;
    }
    for (const auto& m : triangle_methods<float>()) {
      Vec3f vf[3] = {Vec3f(v[0]), Vec3f(v[1]), Vec3f(v[2])};
      const Ray rf = make_ray<float>({0.25f, 0.25f, 0}, {0, 0, 1});
      EXPECT_FALSE(m.fn(rf, vf[0], vf[1], vf[2]).hit) << m.name << " vertex field " << k;
    }
  }
  const Rayd s_ray = make_ray<double>({0, 0, 0}, {0, 0, 1});
  for (const auto& m : sphere_methods<double>()) {
    EXPECT_FALSE(m.fn(s_ray, Vec3d{0, 0, 4}, nan).hit) << m.name;
    EXPECT_FALSE(m.fn(s_ray, Vec3d{nan, 0, 4}, 2.0).hit) << m.name;
    EXPECT_FALSE(m.fn(s_ray, Vec3d{0, 0, nan}, 2.0).hit) << m.name;
  }
  Quadric<double> cyl = Quadric<double>::cylinder({0, 0, 0}, 2, 2, 1);
  const Rayd q_ray = make_ray<double>({5, 0, 0}, {-1, 0, 0});
  for (double Quadric<double>::*coef :
       {&Quadric<double>::A, &Quadric<double>::B, &Quadric<double>::C, &Quadric<double>::D,
        &Quadric<double>::E, &Quadric<double>::F, &Quadric<double>::G, &Quadric<double>::H,
        &Quadric<double>::I, &Quadric<double>::J}) {
    Quadric<double> q = cyl;
    q.*coef = nan;
    EXPECT_FALSE(intersect_quadric(q_ray, q).hit);
  }
  cyl.clip.lo.y = nan;
  EXPECT_FALSE(intersect_quadric(q_ray, cyl).hit);
  Box3d box({-2, -2, -2}, {2, 2, 2});
  box.hi.z = nan;
  const SlabHit<double> bh = intersect_box(make_ray<double>({-3, 0, 0}, {1, 0, 0}), box);
  EXPECT_FALSE(bh.hit);
  EXPECT_FALSE(std::isnan(bh.t_enter) || std::isnan(bh.t_exit));
  std::vector<Vec3d> square = {{-1, -1, 2}, {1, -1, 2}, {1, 1, 2}, {-1, 1, 2}};
  square[2].x = nan;
  const PolygonPlane<double> plane = polygon_plane(as_span(square));
  EXPECT_FALSE(intersect_polygon_convex(up, square, plane).hit);
  EXPECT_FALSE(intersect_polygon_even_odd(up, square, plane).hit);
}

template <typename T>
void check_interval_ends() {
  const T inf = kInfT<T>;
  for (const RoutineCase<T>& c : routine_cases<T>()) {
    const T t = c.t_exact;
    const auto with = [&](T tnear, T tfar) {
      RayT<T> r = c.ray;
      r.tnear = tnear;
      r.tfar = tfar;
      return c.run(r);
    };
    // A hit exactly at tnear or exactly at tfar is accepted, with that exact t.
    const Intersection<T> at_near = with(t, inf);
    ASSERT_TRUE(at_near.hit) << c.name;
    EXPECT_EQ(at_near.t, t) << c.name;
    const Intersection<T> at_far = with(T(0), t);
    ASSERT_TRUE(at_far.hit) << c.name;
    EXPECT_EQ(at_far.t, t) << c.name;
    const Intersection<T> point = with(t, t);
    ASSERT_TRUE(point.hit) << c.name;
    EXPECT_EQ(point.t, t) << c.name;
    // One ulp before the hit: rejected.
    EXPECT_FALSE(with(T(0), std::nextafter(t, T(0))).hit) << c.name;
    // One ulp past the first root: the second root if there is one, else a miss
    // (the box's entry t_enter = 1 stays the raw value while the interval still overlaps).
    const Intersection<T> past = with(std::nextafter(t, inf), inf);
    if (c.name == "box") {
      ASSERT_TRUE(past.hit);
      EXPECT_EQ(past.t, t);
      EXPECT_TRUE(with(T(5), inf).hit);
      EXPECT_FALSE(with(std::nextafter(T(5), inf), inf).hit);
    } else if (c.t_second != t) {
      ASSERT_TRUE(past.hit) << c.name;
      EXPECT_EQ(past.t, c.t_second) << c.name;
      EXPECT_TRUE(with(c.t_second, c.t_second).hit) << c.name;
      EXPECT_FALSE(with(std::nextafter(c.t_second, inf), inf).hit) << c.name;
    } else {
      EXPECT_FALSE(past.hit) << c.name;
    }
  }
}

TEST(IntervalEnds, HitExactlyAtTnearOrTfarIsAcceptedAndJustOutsideIsNotDouble) {
  check_interval_ends<double>();
}

TEST(IntervalEnds, HitExactlyAtTnearOrTfarIsAcceptedAndJustOutsideIsNotFloat) {
  check_interval_ends<float>();
}

TEST(IntervalEnds, HitAtInfinityIsNotReported) {
  // Direction so short that t overflows: the plane is hit "at infinity", which is a miss.
  const Rayd r = make_ray<double>({0, 0, 0}, {0, 0, 1e-310});
  EXPECT_FALSE(intersect_plane(r, Vec3d{0, 0, 1}, -1e10).hit);
  EXPECT_FALSE(in_ray_interval(make_ray<double>({0, 0, 0}, {1, 0, 0}), kInfT<double>));
  EXPECT_TRUE(in_ray_interval(make_ray<double>({0, 0, 0}, {1, 0, 0}), 0.0));
}

}  // namespace
}  // namespace rp
