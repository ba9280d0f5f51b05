#pragma once
/// General quadric surfaces clipped by an axis-aligned box, with named constructors for the
/// common axis-aligned shapes.

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

#include "base/bbox.h"
#include "base/math.h"
#include "core/geometry/intersection.h"
#include "core/ray.h"

namespace rp {

/// The quadric A x^2 + B y^2 + C z^2 + D xy + E yz + F xz + G x + H y + I z + J = 0 in
/// coordinates (x, y, z) = P - center, restricted to the world-space points P inside the
/// closed box `clip`. 10 + 3 + 6 scalars (76 bytes for float).
///
/// Why a center: expanding a translated shape into world-space coefficients makes J and the
/// linear terms large and the evaluation cancel catastrophically (a unit cylinder at x = 1000
/// has J ~ 1e6 in float). Evaluating relative to the center keeps every term the size of the
/// shape, so the error of f and of the roots stays relative to the shape, not to its position.
///
/// Named constructors take a center (a translation), the shape's parameters (lengths in
/// world units, all > 0) and `axis` in {0, 1, 2} = {x, y, z} (values outside are clamped),
/// the symmetry axis k. The two other axes, in increasing index order, are the radial axes
/// i < j: a goes with i and b with j (axis 1 = y: a along x, b along z). Below, x_i, x_j, x_k
/// are coordinates relative to the center.
/// Clip boxes: extents that only bound the surface (radial extents, closed ends) are widened
/// by 1e-4 of the shape's size plus 64 ulps of the centre's magnitude: the surface never
/// reaches them, so widening changes no exact answer, while the rounding error of a computed
/// hit point (a few ulps of |org| + |t dir|, more near grazing) never clips a genuine surface
/// point. Extents that cut the surface (half_height, height) are exact.
template <typename T>
struct Quadric {
  T A = 0, B = 0, C = 0, D = 0, E = 0, F = 0, G = 0, H = 0, I = 0, J = 0;
  /// Origin of the coordinates the coefficients are written in (world space).
  Vec3<T> center{T(0)};
  /// Closed clip box; the default box is all of space.
  Box3<T> clip{Vec3<T>(-std::numeric_limits<T>::infinity()),
               Vec3<T>(std::numeric_limits<T>::infinity())};

  // The evaluations take points with coordinates of type P: T itself, or lanes of T (several
  // points against this one quadric, the renderer's 8-wide shading), with the same operations
  // in the same order, so every lane has T's bits.

  /// Value of the implicit function at world point w: 0 on the surface, its sign tells the side.
  template <class P = T>
  constexpr P eval(const Vec3<P>& w) const {
    return eval_local(w - Vec3<P>(center));
  }

  /// Value of the implicit function at p = P - center.
  template <class P = T>
  constexpr P eval_local(const Vec3<P>& p) const {
    return P(A) * p.x * p.x + P(B) * p.y * p.y + P(C) * p.z * p.z + P(D) * p.x * p.y + P(E) * p.y * p.z +
           P(F) * p.x * p.z + P(G) * p.x + P(H) * p.y + P(I) * p.z + P(J);
  }

  /// Gradient of eval at world point w: the unnormalized surface normal, pointing towards
  /// eval > 0.
  template <class P = T>
  constexpr Vec3<P> gradient(const Vec3<P>& w) const {
    return gradient_local(w - Vec3<P>(center));
  }

  /// Gradient at p = P - center: (2Ax + Dy + Fz + G, 2By + Dx + Ez + H, 2Cz + Ey + Fx + I).
  template <class P = T>
  constexpr Vec3<P> gradient_local(const Vec3<P>& p) const {
    return {P(T(2) * A) * p.x + P(D) * p.y + P(F) * p.z + P(G), P(T(2) * B) * p.y + P(D) * p.x + P(E) * p.z + P(H),
            P(T(2) * C) * p.z + P(E) * p.y + P(F) * p.x + P(I)};
  }

  /// World-space bounds of the clipped surface: the clip box.
  constexpr Box3<T> bounds() const { return clip; }

  /// The same surface with every coefficient multiplied by the power of two that brings the
  /// largest |A..J| into [1, 2): each value the tests compute is scaled exactly, and the
  /// products of a valid ray (core/ray.h) cannot overflow. A quadric whose coefficients
  /// are all 0 (or not finite) is returned unchanged.
  Quadric normalized() const {
    Quadric q = *this;
    T* terms[] = {&q.A, &q.B, &q.C, &q.D, &q.E, &q.F, &q.G, &q.H, &q.I, &q.J};
    T largest = 0;
    for (const T* t : terms) largest = std::max(largest, std::abs(*t));
    if (!(largest > T(0)) || !std::isfinite(largest)) return q;
    int exponent = 0;
    std::frexp(largest, &exponent);  // largest = m 2^exponent, m in [0.5, 1)
    for (T* t : terms) *t = std::ldexp(*t, 1 - exponent);
    return q;
  }

  /// Ellipsoid (x/rx)^2 + (y/ry)^2 + (z/rz)^2 = 1 around center, radii = (rx, ry, rz).
  /// Clip: center +- radii (the natural bounds). No axis parameter: radii name every axis.
  static Quadric ellipsoid(const Vec3<T>& center, const Vec3<T>& radii) {
    const Vec3<T> alpha{T(1) / (radii.x * radii.x), T(1) / (radii.y * radii.y),
                        T(1) / (radii.z * radii.z)};
    return axis_aligned(center, alpha, Vec3<T>(T(0)), T(-1),
                        padded_box(center, -radii, radii, {true, true, true}, {true, true, true}));
  }

  /// Elliptic cylinder (x_i/radius_a)^2 + (x_j/radius_b)^2 = 1 for |x_k| <= half_height
  /// (open: no caps). Clip: +-radius_a, +-radius_b, +-half_height.
  static Quadric cylinder(const Vec3<T>& center, T radius_a, T radius_b, T half_height,
                          int axis = 1) {
    const Axes ax = axes(axis);
    Vec3<T> alpha(T(0));
    alpha[ax.i] = T(1) / (radius_a * radius_a);
    alpha[ax.j] = T(1) / (radius_b * radius_b);
    return axis_aligned(center, alpha, Vec3<T>(T(0)), T(-1),
                        radial_clip(center, ax, radius_a, radius_b, -half_height, half_height,
                                    false, false));
  }

  /// Double elliptic cone (x_i/a)^2 + (x_j/b)^2 = x_k^2 with the apex at center, clipped to
  /// |x_k| <= half_height. a and b are slopes: at height h the cross-section is the ellipse
  /// with semi-axes a|h| and b|h| (a = b = tan of the half-opening angle for a circular cone).
  /// Clip: +-a*half_height, +-b*half_height, +-half_height.
  static Quadric cone(const Vec3<T>& center, T a, T b, T half_height, int axis = 1) {
    const Axes ax = axes(axis);
    Vec3<T> alpha(T(0));
    alpha[ax.i] = T(1) / (a * a);
    alpha[ax.j] = T(1) / (b * b);
    alpha[ax.k] = T(-1);
    return axis_aligned(center, alpha, Vec3<T>(T(0)), T(0),
                        radial_clip(center, ax, a * half_height, b * half_height, -half_height,
                                    half_height, false, false));
  }

  /// Hyperboloid of one sheet (x_i/a)^2 + (x_j/b)^2 - (x_k/c)^2 = 1, clipped to
  /// |x_k| <= half_height; waist ellipse (a, b) at x_k = 0.
  /// Clip: +-a*s, +-b*s with s = sqrt(1 + (half_height/c)^2), +-half_height.
  static Quadric hyperboloid_one_sheet(const Vec3<T>& center, T a, T b, T c, T half_height,
                                       int axis = 1) {
    const Axes ax = axes(axis);
    Vec3<T> alpha(T(0));
    alpha[ax.i] = T(1) / (a * a);
    alpha[ax.j] = T(1) / (b * b);
    alpha[ax.k] = T(-1) / (c * c);
    const T hc = half_height / c;
    const T s = std::sqrt(T(1) + hc * hc);
    return axis_aligned(center, alpha, Vec3<T>(T(0)), T(-1),
                        radial_clip(center, ax, a * s, b * s, -half_height, half_height, false,
                                    false));
  }

  /// Hyperboloid of two sheets (x_k/c)^2 - (x_i/a)^2 - (x_j/b)^2 = 1, clipped to
  /// |x_k| <= half_height; the sheets' vertices are at x_k = +-c (nothing remains when
  /// half_height < c). Clip: +-a*s, +-b*s with s = sqrt(max(0, (half_height/c)^2 - 1)),
  /// +-half_height.
  static Quadric hyperboloid_two_sheets(const Vec3<T>& center, T a, T b, T c, T half_height,
                                        int axis = 1) {
    const Axes ax = axes(axis);
    Vec3<T> alpha(T(0));
    alpha[ax.i] = T(-1) / (a * a);
    alpha[ax.j] = T(-1) / (b * b);
    alpha[ax.k] = T(1) / (c * c);
    const T hc = half_height / c;
    const T s = std::sqrt(std::max(T(0), hc * hc - T(1)));
    return axis_aligned(center, alpha, Vec3<T>(T(0)), T(-1),
                        radial_clip(center, ax, a * s, b * s, -half_height, half_height, false,
                                    false));
  }

  /// Elliptic paraboloid (x_i/a)^2 + (x_j/b)^2 = x_k / height with the vertex at center,
  /// opening along +axis, clipped to 0 <= x_k <= height; a and b are the semi-axes of the
  /// rim ellipse at x_k = height. Clip: +-a, +-b, [0, height].
  static Quadric paraboloid(const Vec3<T>& center, T a, T b, T height, int axis = 1) {
    const Axes ax = axes(axis);
    Vec3<T> alpha(T(0));
    alpha[ax.i] = T(1) / (a * a);
    alpha[ax.j] = T(1) / (b * b);
    Vec3<T> beta(T(0));
    beta[ax.k] = T(-1) / height;
    return axis_aligned(center, alpha, beta, T(0),
                        radial_clip(center, ax, a, b, T(0), height, true, false));
  }

 private:
  struct Axes {
    int i, j, k;
  };
  static constexpr Axes axes(int axis) {
    const int k = std::clamp(axis, 0, 2);
    return {k == 0 ? 1 : 0, k == 2 ? 1 : 2, k};
  }

  /// sum_m alpha_m (x_m - c_m)^2 + beta_m (x_m - c_m) + gamma, written around center c.
  static Quadric axis_aligned(const Vec3<T>& c, const Vec3<T>& alpha, const Vec3<T>& beta,
                              T gamma, const Box3<T>& clip) {
    Quadric q;
    q.A = alpha.x;
    q.B = alpha.y;
    q.C = alpha.z;
    q.G = beta.x;
    q.H = beta.y;
    q.I = beta.z;
    q.J = gamma;
    q.center = c;
    q.clip = clip;
    return q;
  }

  /// Box c + [lo, hi]; the ends flagged in pad_lo / pad_hi are widened by 1e-4 of the
  /// extent plus 64 ulps of |c| (see the class comment).
  static Box3<T> padded_box(const Vec3<T>& c, const Vec3<T>& lo, const Vec3<T>& hi,
                            const Vec3<bool>& pad_lo, const Vec3<bool>& pad_hi) {
    const T ulps = T(64) * std::numeric_limits<T>::epsilon();
    Box3<T> box{c + lo, c + hi};
    for (int m = 0; m < 3; ++m) {
      const T slack = ulps * std::abs(c[m]) + T(1e-4) * std::max(std::abs(lo[m]), std::abs(hi[m]));
      if (pad_lo[m]) box.lo[m] -= slack;
      if (pad_hi[m]) box.hi[m] += slack;
    }
    return box;
  }

  /// Clip with radial half extents ea (axis i), eb (axis j), padded, and axial range
  /// [k_lo, k_hi] relative to c, padded where flagged.
  static Box3<T> radial_clip(const Vec3<T>& c, const Axes& ax, T ea, T eb, T k_lo, T k_hi,
                             bool pad_k_lo, bool pad_k_hi) {
    Vec3<T> lo, hi;
    Vec3<bool> pad_lo{true, true, true}, pad_hi{true, true, true};
    lo[ax.i] = -ea;
    hi[ax.i] = ea;
    lo[ax.j] = -eb;
    hi[ax.j] = eb;
    lo[ax.k] = k_lo;
    hi[ax.k] = k_hi;
    pad_lo[ax.k] = pad_k_lo;
    pad_hi[ax.k] = pad_k_hi;
    return padded_box(c, lo, hi, pad_lo, pad_hi);
  }
};

using Quadricf = Quadric<float>;
using Quadricd = Quadric<double>;

/// `q` with every coefficient, the center and the clip box converted to To (exactly, for float
/// to double: the double-precision reference and the tests evaluate the very float quadric).
template <typename To, typename From>
constexpr Quadric<To> quadric_cast(const Quadric<From>& q) {
  Quadric<To> d;
  d.A = To(q.A); d.B = To(q.B); d.C = To(q.C); d.D = To(q.D); d.E = To(q.E);
  d.F = To(q.F); d.G = To(q.G); d.H = To(q.H); d.I = To(q.I); d.J = To(q.J);
  d.center = Vec3<To>(q.center);
  d.clip = Box3<To>(Vec3<To>(q.clip.lo), Vec3<To>(q.clip.hi));
  return d;
}

/// A ray whose direction is divided by the power of two `scale` that brings its largest
/// |component| into [1, 2), with tnear and tfar multiplied by it: the same points at the
/// scaled parameters, and every product with the direction scaled exactly (no rounding
/// changes unless a value leaves float's normal range).
template <typename T>
struct ScaledRay {
  RayT<T> ray;
  T scale;
  /// A hit of the scaled ray as a hit of the caller's: t divided back, exactly.
  Intersection<T> unscaled(Intersection<T> h) const {
    if (h.hit) h.t /= scale;
    return h;
  }
};

template <typename T>
ScaledRay<T> direction_scaled(const RayT<T>& r) {
  const T largest = std::max(std::abs(r.dir.x), std::max(std::abs(r.dir.y), std::abs(r.dir.z)));
  if (!(largest > T(0)) || !std::isfinite(largest)) return {r, T(1)};
  int exponent = 0;
  std::frexp(largest, &exponent);  // largest = m 2^exponent, m in [0.5, 1)
  const T scale = std::ldexp(T(1), exponent - 1);
  return {{r.org, r.tnear * scale, r.dir / scale, r.tfar * scale}, scale};
}

/// Coefficients of a t^2 + b t + c = 0 for r against q, with the origin in the quadric's
/// coordinates (org - center). Lecture notes, "Ray-Quadric Surface Intersection": substitute
/// P(t) = o + t d into the quadric:
///   a = A dx^2 + B dy^2 + C dz^2 + D dx dy + E dy dz + F dx dz   (the quadratic form at d)
///   b = 2(A ox dx + B oy dy + C oz dz) + D(ox dy + oy dx) + E(oy dz + oz dy)
///       + F(ox dz + oz dx) + G dx + H dy + I dz                  (= gradient(o) . d)
///   c = eval(o).
template <typename T>
std::array<T, 3> quadric_coefficients(const RayT<T>& r, const Quadric<T>& q) {
  const Vec3<T> o = r.org - q.center;
  const Vec3<T>& d = r.dir;
  const T a = q.A * d.x * d.x + q.B * d.y * d.y + q.C * d.z * d.z + q.D * d.x * d.y +
              q.E * d.y * d.z + q.F * d.x * d.z;
  return {a, dot(q.gradient_local(o), d), q.eval_local(o)};
}

/// The first of the roots t0 <= t1 in [tnear, tfar] whose point lies in q.clip, else a miss.
template <typename T>
Intersection<T> quadric_pick_root(const RayT<T>& r, const Quadric<T>& q, T t0, T t1) {
  if (in_ray_interval(r, t0) && q.clip.contains(r.at(t0))) return make_intersection(t0);
  if (in_ray_interval(r, t1) && q.clip.contains(r.at(t1))) return make_intersection(t1);
  return {};
}

/// Closest hit of r with the clipped quadric q; u == v == 0.
/// Accepts the smaller root in [r.tnear, r.tfar] whose point lies in q.clip (closed), else
/// the larger one. Miss: no such root, a ray lying in a degenerate direction of the surface
/// (a == b == 0), or NaN anywhere. The ray origin is moved into the quadric's coordinates
/// (org - center) first, so precision follows the shape's size rather than its position.
/// The direction is scaled by a power of two (direction_scaled): b^2 - 4ac then stays finite
/// for every valid ray (core/ray.h) while every computed value is the unscaled one's,
/// scaled exactly.
template <typename T>
Intersection<T> intersect_quadric(const RayT<T>& ray, const Quadric<T>& q) {
  const ScaledRay<T> sr = direction_scaled(ray);
  const RayT<T>& r = sr.ray;
  const auto [a, b, c] = quadric_coefficients(r, q);
  T t0, t1;
  if (a == T(0)) {
    // Linear case: the direction is asymptotic to the surface. One root -c/b; b == 0 too
    // means the line lies in the surface or never meets it: miss (as a parallel plane).
    if (b == T(0)) return {};
    t0 = t1 = -c / b;
  } else {
    // Numerically stable roots (Press et al., Numerical Recipes, 3rd ed., section 5.6):
    // q = -(b + sign(b) sqrt(b^2 - 4ac)) / 2, roots q/a and c/q. For tiny a the root c/q
    // stays accurate (it tends to -c/b) and q/a runs off to a large or infinite value.
    const T disc = b * b - T(4) * a * c;
    if (!(disc >= T(0))) return {};
    const T qq = T(-0.5) * (b + std::copysign(std::sqrt(disc), b));
    if (qq == T(0)) {
      t0 = t1 = T(0);  // b == 0 and disc == 0: the double root t = 0
    } else {
      t0 = qq / a;
      t1 = c / qq;
      if (t1 < t0) std::swap(t0, t1);
    }
  }
  return sr.unscaled(quadric_pick_root(r, q, t0, t1));
}

/// The same test with the textbook roots (-b -+ sqrt(b^2 - 4ac)) / 2a (the lecture notes' algebraic
/// method): cancellation when b^2 >> 4ac loses the near root of a far or grazing ray. Kept as
/// the baseline `raypack stability` measures; raypack renders with intersect_quadric.
template <typename T>
Intersection<T> intersect_quadric_naive(const RayT<T>& ray, const Quadric<T>& q) {
  const ScaledRay<T> sr = direction_scaled(ray);
  const RayT<T>& r = sr.ray;
  const auto [a, b, c] = quadric_coefficients(r, q);
  if (a == T(0)) {
    if (b == T(0)) return {};
    return sr.unscaled(quadric_pick_root(r, q, -c / b, -c / b));
  }
  const T disc = b * b - T(4) * a * c;
  if (!(disc >= T(0))) return {};
  const T s = std::sqrt(disc);
  T t0 = (-b - s) / (T(2) * a), t1 = (-b + s) / (T(2) * a);
  if (t1 < t0) std::swap(t0, t1);
  return sr.unscaled(quadric_pick_root(r, q, t0, t1));
}

}  // namespace rp
