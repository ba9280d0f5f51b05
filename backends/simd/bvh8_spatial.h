#pragma once
/// Spatial splits (SBVH: Stich, Friedrich and Dietrich, "Spatial Splits in Bounding Volume
/// Hierarchies", HPG 2009; BuildOptions::spatial_splits): where a node's best object split
/// leaves overlapping children, a cut of space at a plane, a triangle crossing it going to
/// both sides with its box clipped there. Internal to the builder (bvh8_*.cpp).

#include "backends/simd/bvh8_binned_sah.h"

namespace rp::bvh8::build_detail {

/// Overlap of a node's children below which no spatial split is tried, relative to the root's
/// area (Stich et al.'s alpha): only where object splits leave children overlapping does
/// cutting space pay for the references it adds. Stich et al. use 1e-5; measured, 1e-3 keeps
/// nearly all of the SAH gain and the diffuse-ray speed, with a much shorter build and fewer
/// references (figures: docs/notes/2026-11-29-figures-from-code-comments.md).
constexpr float kMinOverlap = 1e-3f;

/// Area where the two sides of an object split overlap (0 when there is none: o.axis < 0).
float overlap(const BinnedSplit& o);

/// The best spatial split of the triangle refs `v` under `box`: per axis, bins between
/// equally spaced planes, each ref entering the bin of its low end and leaving by that of
/// its high end, its box chopped at every plane in between (Stich et al., sec. 4).
BinnedSplit spatial_split(const CornerSource& corners, const RefArray& v, const Box3f& box);

/// Sends each ref of `v` to the side of the split's plane it lies on, a ref crossing it to
/// both as its two clipped parts (a part with an empty box is dropped). False when a side
/// would be empty.
bool divide(const CornerSource& corners, const RefArray& v, const BinnedSplit& s, const Box3f& box, RefArray& left,
            RefArray& right);

}  // namespace rp::bvh8::build_detail
