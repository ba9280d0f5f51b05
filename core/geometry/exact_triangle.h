#pragma once
/// The ray/triangle test whose edge decisions are exact: on which side of each edge a ray
/// passes is the sign of the exact determinant of the float inputs, never a rounded one. Two
/// triangles sharing an edge compute one determinant for it (negated), and the triangles
/// around a shared vertex see the ray on consistent sides of their edges, so a ray that
/// crosses a closed mesh's surface always hits one of its triangles: no leak through shared
/// edges or vertices, at any translation or scale. The watertight variant of the simd backend
/// runs this test on the lanes its bounded filter leaves uncertain (backends/simd/watertight.h).

#include "base/math.h"
#include "core/geometry/intersection.h"
#include "core/ray.h"

namespace rp {

/// The sign (-1, 0 or 1) of the exact ((p - o) x (q - o)) . d: on which side of the line
/// through p and q the ray from o along d passes (0: through the line, or d parallel to the
/// plane of p, q and o). Antisymmetric in p and q. A double-precision evaluation with a
/// forward error bound decides whenever its value is farther from 0 than the bound; otherwise
/// the determinant is evaluated in integers (GMP), exactly. 0 for a NaN or infinite input.
int edge_side(const Vec3f& p, const Vec3f& q, const Vec3f& o, const Vec3f& d);

/// Whether a ray passes inside a triangle whose edges (v2, v0), (v0, v1), (v1, v2) it passes
/// on the sides su, sv, sw (edge_side): all >= 0 or all <= 0, and not all 0 (the three exact
/// edge functions then sum to a nonzero determinant).
constexpr bool inside_edges(int su, int sv, int sw) {
  const bool none = su == 0 && sv == 0 && sw == 0;
  return !none && ((su >= 0 && sv >= 0 && sw >= 0) || (su <= 0 && sv <= 0 && sw <= 0));
}

/// The ray/triangle test of the contract of core/geometry/triangle.h with exact edge
/// decisions: the ray passes inside by inside_edges of its edge sides (edge_side). t, u and v
/// are computed in double from the same floats (Möller–Trumbore's normal-first factoring,
/// t = Ng.(v0 - o) / Ng.d, u and v the edge functions over their sum, clamped to the
/// triangle) and rounded once; the hit needs that t finite and within [tnear, tfar]. A NaN or
/// infinite input misses.
Intersection<float> intersect_triangle_exact(const Ray& r, const Vec3f& v0, const Vec3f& v1, const Vec3f& v2);

}  // namespace rp
