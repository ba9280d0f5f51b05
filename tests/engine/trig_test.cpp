// The cameras' sin, cos and atan2 (base/trig.h) against the exact values (double precision),
// over their whole domain and densely near the points where the reduction changes quadrant:
// the largest error in units in the last place of the float result stays within a stated bound.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "base/trig.h"

namespace rp {
namespace {

/// |got - want| in ulps of want as a float (the spacing at |want|, at least the smallest normal's).
double ulps(float got, double want) {
  const float w = float(want);
  const double spacing =
      std::max(double(std::nextafter(std::abs(w), std::numeric_limits<float>::infinity()) - std::abs(w)),
               double(std::numeric_limits<float>::min()));
  return std::abs(double(got) - want) / spacing;
}

struct Worst {
  double ulps = 0;
  float at = 0;
  void add(double u, float x) {
    if (u > ulps) {
      ulps = u;
      at = x;
    }
  }
};

/// Every 2^-10 of [-8, 8], each multiple of pi/4 in it and its 16 float neighbours on each
/// side, and 200,000 random arguments.
std::vector<float> arguments() {
  std::vector<float> xs;
  for (int i = -8192; i <= 8192; ++i) xs.push_back(float(i) / 1024.0f);
  for (int k = -10; k <= 10; ++k) {
    float x = float(k * M_PI / 4);
    for (int j = 0; j < 16; ++j) x = std::nextafter(x, -10.0f);
    for (int j = 0; j < 33; ++j, x = std::nextafter(x, 10.0f)) xs.push_back(x);
  }
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-8.0f, 8.0f);
  for (int i = 0; i < 200000; ++i) xs.push_back(u(rng));
  return xs;
}

TEST(Trig, SinAndCosStayWithinTwoUlpsOnTheirDomain) {
  Worst ws, wc;
  double abs_err = 0;
  for (const float x : arguments()) {
    float s, c;
    sincos_lanes<float>(x, s, c);
    const double es = std::sin(double(x)), ec = std::cos(double(x));
    // Near a zero of sin or cos the relative error of any float routine grows (the argument
    // itself is rounded); there the absolute error is bounded instead.
    if (std::abs(es) > 1e-3) ws.add(ulps(s, es), x);
    if (std::abs(ec) > 1e-3) wc.add(ulps(c, ec), x);
    abs_err = std::max({abs_err, std::abs(double(s) - es), std::abs(double(c) - ec)});
  }
  std::printf("[ trig ] sin: worst %.2f ulps (at %.9g), cos: worst %.2f ulps (at %.9g), absolute %.3g\n", ws.ulps,
              double(ws.at), wc.ulps, double(wc.at), abs_err);
  EXPECT_LE(ws.ulps, 2.0);
  EXPECT_LE(wc.ulps, 2.0);
  EXPECT_LE(abs_err, 2e-7);
}

TEST(Trig, Atan2StaysWithinThreeUlpsInEveryQuadrant) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> angle(-3.14159f, 3.14159f), radius(1e-3f, 10.0f);
  Worst w;
  for (int i = 0; i < 400000; ++i) {
    const float a = angle(rng), r = radius(rng);
    const float x = r * std::cos(a), y = r * std::sin(a);
    const double want = std::atan2(double(y), double(x));
    w.add(ulps(atan2_lanes<float>(y, x), want), a);
  }
  // The axes and the diagonals exactly.
  for (const float y : {-2.0f, -1.0f, 0.0f, 1.0f, 2.0f})
    for (const float x : {-2.0f, -1.0f, 1.0f, 2.0f})
      w.add(ulps(atan2_lanes<float>(y, x), std::atan2(double(y), double(x))), y);
  std::printf("[ trig ] atan2: worst %.2f ulps\n", w.ulps);
  EXPECT_LE(w.ulps, 3.0);  // the division and the polynomial each round (measured: 2.44)
  EXPECT_EQ(atan2_lanes<float>(0.0f, 0.0f), 0.0f);
  EXPECT_EQ(atan2_lanes<float>(0.0f, -1.0f), float(M_PI));
}

}  // namespace
}  // namespace rp
