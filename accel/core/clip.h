// SPDX-License-Identifier: MIT
// Clipping a triangle to an axis-aligned box (Sutherland-Hodgman), in double precision.
// Used by EPO and by spatial-split builders, which need exact clipped bounds.
#pragma once

#include "accel/core/aabb.h"

namespace bvhlab::accel {

/// Result of clipping one triangle to a box: the clipped polygon's area and bounds.
struct ClipResult {
    double area = 0.0;        ///< area of the part of the triangle inside the box
    AABB bounds = AABB::empty();  ///< bounds of that part; empty when nothing is inside
};

ClipResult clip_triangle(Vec3 a, Vec3 b, Vec3 c, const AABB& box);

}  // namespace bvhlab::accel
