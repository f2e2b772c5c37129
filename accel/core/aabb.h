// SPDX-License-Identifier: MIT
// Axis-aligned bounding box shared by builders, stats and layouts.
#pragma once

#include <cfloat>

#include "accel/core/hd.h"
#include "accel/core/vec3.h"

namespace bvhlab {

/// Axis-aligned box, 24 bytes. An empty box has lo = +FLT_MAX and hi = -FLT_MAX.
struct AABB {
    Vec3 lo;  // 12 bytes
    Vec3 hi;  // 12 bytes: total 24 bytes

    BVHLAB_HD static AABB empty() { return {{FLT_MAX, FLT_MAX, FLT_MAX}, {-FLT_MAX, -FLT_MAX, -FLT_MAX}}; }
    BVHLAB_HD static AABB of_point(Vec3 p) { return {p, p}; }

    BVHLAB_HD bool is_empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
    BVHLAB_HD void extend(Vec3 p) {
        lo = vmin(lo, p);
        hi = vmax(hi, p);
    }
    BVHLAB_HD void extend(const AABB& b) {
        lo = vmin(lo, b.lo);
        hi = vmax(hi, b.hi);
    }
    BVHLAB_HD Vec3 extent() const { return hi - lo; }
    BVHLAB_HD Vec3 center() const { return (lo + hi) * 0.5f; }

    /// Surface area; 0 for an empty box.
    BVHLAB_HD float area() const {
        if (is_empty()) return 0.0f;
        Vec3 e = extent();
        return 2.0f * (e.x * e.y + e.y * e.z + e.z * e.x);
    }
    /// Half the surface area: all SAH ratios use it, the factor 2 cancels.
    BVHLAB_HD float half_area() const {
        if (is_empty()) return 0.0f;
        Vec3 e = extent();
        return e.x * e.y + e.y * e.z + e.z * e.x;
    }
    /// Index of the longest axis (0, 1 or 2).
    BVHLAB_HD int largest_axis() const {
        Vec3 e = extent();
        return (e.x >= e.y && e.x >= e.z) ? 0 : (e.y >= e.z ? 1 : 2);
    }
    /// True when `b` lies inside this box (inclusive).
    BVHLAB_HD bool contains(const AABB& b) const {
        return b.lo.x >= lo.x && b.lo.y >= lo.y && b.lo.z >= lo.z && b.hi.x <= hi.x && b.hi.y <= hi.y && b.hi.z <= hi.z;
    }
    BVHLAB_HD bool overlaps(const AABB& b) const {
        return lo.x <= b.hi.x && b.lo.x <= hi.x && lo.y <= b.hi.y && b.lo.y <= hi.y && lo.z <= b.hi.z && b.lo.z <= hi.z;
    }
};
static_assert(sizeof(AABB) == 24, "AABB is six floats");

BVHLAB_HD inline AABB merge(AABB a, const AABB& b) {
    a.extend(b);
    return a;
}

/// The common part of two boxes; AABB::empty() if they do not overlap.
BVHLAB_HD inline AABB intersect(AABB a, const AABB& b) {
    a.lo = vmax(a.lo, b.lo);
    a.hi = vmin(a.hi, b.hi);
    return a.is_empty() ? AABB::empty() : a;
}

}  // namespace bvhlab
