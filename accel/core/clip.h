// SPDX-License-Identifier: MIT
// Clipping a triangle to an axis-aligned box (Sutherland-Hodgman), in double precision.
// Used by EPO and by spatial-split builders, which need exact clipped bounds.
#pragma once

#include <utility>

#include "accel/core/aabb.h"

namespace bvhlab::accel {

/// Result of clipping one triangle to a box: the clipped polygon's area and bounds.
struct ClipResult {
    double area = 0.0;        ///< area of the part of the triangle inside the box
    AABB bounds = AABB::empty();  ///< bounds of that part; empty when nothing is inside
};

ClipResult clip_triangle(Vec3 a, Vec3 b, Vec3 c, const AABB& box);

/// The bounds of the two parts of triangle abc clipped to `box` that lie below and above the
/// plane x[axis] = pos (perfect splits for a kd-tree): one clip to the box, then one pass over
/// the polygon for both sides. A side the triangle does not reach is empty.
std::pair<AABB, AABB> split_clipped_triangle(Vec3 a, Vec3 b, Vec3 c, const AABB& box, int axis, float pos);

}  // namespace bvhlab::accel
