#pragma once
/// sin, cos and atan2 in lanes (base/lanes.h), for the cameras: one routine for one lane and
/// for eight, so that Camera::generate and its 8-wide twin give every ray the same bits (libm's
/// sinf has no 8-wide twin). Cephes' single-precision polynomials (S. L. Moshier, "Methods and
/// Programs for Mathematical Functions", 1989: sinf, cosf, atanf) after a reduction by pi/2 in
/// three parts. For arguments within [-8, 8] (the cameras' angles lie in [-pi, pi]); the error
/// against the exact value is bounded in tests/engine/trig_test.cpp.

#include "base/lanes.h"
#include "base/math.h"

namespace rp {

/// sin(x) and cos(x) for |x| <= 8.
template <class F>
void sincos_lanes(const F& x, F& s, F& c) {
  using L = Lanes<F>;
  const F k = L::floor(x * F(0.636619772367581343f) + F(0.5f));  // the nearest multiple of pi/2
  // r = x - k pi/2, pi/2 in three parts whose products with k (|k| <= 6) are exact.
  const F r = ((x - k * F(1.5703125f)) - k * F(4.837512969970703125e-4f)) - k * F(7.54978995489188216e-8f);
  const F z = r * r;
  const F sr = ((F(-1.9515295891e-4f) * z + F(8.3321608736e-3f)) * z - F(1.6666654611e-1f)) * z * r + r;
  const F cr = ((F(2.443315711809948e-5f) * z - F(1.388731625493765e-3f)) * z + F(4.166664568298827e-2f)) * z * z -
               F(0.5f) * z + F(1.0f);
  // x = k pi/2 + r: by k mod 4, (sin, cos) = (sr, cr), (cr, -sr), (-sr, -cr), (-cr, sr).
  const F q = k - F(4.0f) * L::floor(k * F(0.25f));
  const auto odd = q == F(1.0f) || q == F(3.0f);
  const F sv = L::select(odd, cr, sr), cv = L::select(odd, sr, cr);
  s = L::select(q >= F(2.0f), -sv, sv);
  c = L::select(q == F(1.0f) || q == F(2.0f), -cv, cv);
}

/// atan2(y, x) in [-pi, pi] (0 for x = y = 0; +pi for y = +-0 and x < 0).
template <class F>
F atan2_lanes(const F& y, const F& x) {
  using L = Lanes<F>;
  const F ax = L::abs(x), ay = L::abs(y);
  const auto steep = ay > ax;
  const F num = L::select(steep, ax, ay), den = L::select(steep, ay, ax);
  const F a = L::select(den > F(0.0f), num / den, F(0.0f));  // in [0, 1]
  // atan(a): above tan(pi/8), pi/4 + atan((a - 1) / (a + 1)).
  const auto upper = a > F(0.414213562373095f);
  const F t = L::select(upper, (a - F(1.0f)) / (a + F(1.0f)), a);
  const F z = t * t;
  const F p =
      (((F(8.05374449538e-2f) * z - F(1.38776856032e-1f)) * z + F(1.99777106478e-1f)) * z - F(3.33329491539e-1f)) * z *
          t +
      t;
  // The multiples of pi added in two parts (float(pi) + the rest), the small part first.
  constexpr float pi = float(kPi), pi_rest = float(kPi - double(float(kPi)));
  F at = L::select(upper, (p + F(0.25f * pi_rest)) + F(0.25f * pi), p);
  at = L::select(steep, (F(0.5f * pi) - at) + F(0.5f * pi_rest), at);
  at = L::select(x < F(0.0f), (F(pi) - at) + F(pi_rest), at);
  return L::select(y < F(0.0f), -at, at);
}

}  // namespace rp
