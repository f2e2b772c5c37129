// SPDX-License-Identifier: MIT
// Clipping a triangle to an axis-aligned box (Sutherland-Hodgman), in double precision.
// Used by EPO and by spatial-split builders, which need exact clipped bounds.
#pragma once

#include <utility>

#include "accel/core/aabb.h"

namespace bvhlab::accel {

/// Result of clipping one triangle to a box: the clipped polygon's area and bounds.
struct ClipResult {
    double area = 0.0;            ///< area of the part of the triangle inside the box
    AABB bounds = AABB::empty();  ///< bounds of that part; empty when nothing is inside
};

ClipResult clip_triangle(Vec3 a, Vec3 b, Vec3 c, const AABB& box);

/// The bounds of the two parts of triangle abc clipped to `box` that lie below and above the
/// plane x[axis] = pos (perfect splits for a kd-tree): one clip to the box, then one pass over
/// the polygon for both sides. A side the triangle does not reach is empty.
std::pair<AABB, AABB> split_clipped_triangle(Vec3 a, Vec3 b, Vec3 c, const AABB& box, int axis, float pos);

/// A vertex of a clipped polygon, in double precision.
struct PolygonVertex {
    double v[3];
};

/// Triangle abc clipped to `box`, as split_clipped_triangle() clips it, into `out` (room for
/// 12 vertices); returns the vertex count.
int clip_triangle_polygon(Vec3 a, Vec3 b, Vec3 c, const AABB& box, PolygonVertex* out);

/// split_clipped_triangle() for a convex polygon p[0, n) that lies in `box` (a triangle
/// clipped to it): the bounds of its parts below and above x[axis] = pos, and the parts
/// themselves in below[0, *n_below) and above[0, *n_above) (each with room for 2 n vertices).
/// Splitting the parts again gives the same bounds, to rounding, as clipping the triangle to
/// the smaller box anew.
std::pair<AABB, AABB> split_polygon(const PolygonVertex* p, int n, const AABB& box, int axis, float pos,
                                    PolygonVertex* below, int* n_below, PolygonVertex* above, int* n_above);

}  // namespace bvhlab::accel
