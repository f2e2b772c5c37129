// SPDX-License-Identifier: MIT
// Spatial-split binning (Stich, Friedrich & Dietrich 2009, "Spatial splits in bounding volume
// hierarchies"): references are chopped at bin boundaries by clipping their triangle, so each
// bin holds the exact bounds of the pieces inside it.
#pragma once

#include <cstdint>

#include "accel/core/binning.h"
#include "accel/core/prim_ref.h"

namespace bvhlab::accel {

/// The part of `box` on one side of the plane x[axis] = pos.
inline AABB clamp_box(AABB box, int axis, float pos, bool keep_left) {
    if (keep_left) box.hi[axis] = min_f(box.hi[axis], pos);
    else box.lo[axis] = max_f(box.lo[axis], pos);
    return box;
}

/// Splits a reference at the plane x[axis] = pos (Stich et al., section 4.4): the triangle's
/// vertices and its edges' crossings of the plane go to the side(s) they lie on, and each side
/// is intersected with the reference's current bounds. O(1) per plane, unlike a full polygon
/// clip against a box; exact up to the reference's earlier splits. Either side may be empty.
inline void split_reference(const TriangleMesh& mesh, const PrimRef& r, int axis, float pos, AABB& left,
                            AABB& right) {
    left = right = AABB::empty();
    Vec3 v[3] = {mesh.vertex(r.prim_id, 0), mesh.vertex(r.prim_id, 1), mesh.vertex(r.prim_id, 2)};
    for (int i = 0; i < 3; ++i) {
        const Vec3 a = v[i], b = v[(i + 1) % 3];
        if (a[axis] <= pos) left.extend(a);
        if (a[axis] >= pos) right.extend(a);
        if ((a[axis] < pos && b[axis] > pos) || (a[axis] > pos && b[axis] < pos)) {
            const double t = (double(pos) - a[axis]) / (double(b[axis]) - a[axis]);
            Vec3 p;
            for (int k = 0; k < 3; ++k) p[k] = float(double(a[k]) + t * (double(b[k]) - a[k]));
            p[axis] = pos;
            left.extend(p);
            right.extend(p);
        }
    }
    auto intersect = [](AABB x, const AABB& y) {
        x.lo = vmax(x.lo, y.lo);
        x.hi = vmin(x.hi, y.hi);
        return x.is_empty() ? AABB::empty() : x;
    };
    left = intersect(left, clamp_box(r.bounds, axis, pos, true));
    right = intersect(right, clamp_box(r.bounds, axis, pos, false));
}

/// Equal-width bins over [lo, hi) of one axis of a node's bounds, with entry and exit counts.
struct SpatialBins {
    int axis = 0;
    int count = 0;
    float lo = 0.0f, width = 0.0f;
    Bin bins[kMaxBins];
    uint32_t entry[kMaxBins];  ///< references whose piece starts in the bin
    uint32_t exit[kMaxBins];   ///< references whose piece ends in the bin

    SpatialBins(int axis_, int count_, const AABB& node) : axis(axis_), count(count_), lo(node.lo[axis_]) {
        width = (node.hi[axis] - lo) / float(count);
        for (int i = 0; i < count; ++i) {
            bins[i] = Bin::empty();
            entry[i] = exit[i] = 0;
        }
    }
    int bin_of(float x) const {
        int i = width > 0.0f ? int((x - lo) / width) : 0;
        return i < 0 ? 0 : (i >= count ? count - 1 : i);
    }
    /// Position of the plane after bin i.
    float plane(int i) const { return lo + width * float(i + 1); }

    /// Adds one reference, chopped at every bin boundary it crosses. The piece in bin i is
    /// the box of the triangle's part between the bin's planes (its vertices there and its
    /// edges' crossings of both planes), cut to the reference's bounds. Each plane's crossings
    /// are computed once and shared by the bins on either side; the triangle is read once.
    void add(const TriangleMesh& mesh, const PrimRef& r) {
        const int first = bin_of(r.bounds.lo[axis]), last = bin_of(r.bounds.hi[axis]);
        ++entry[first];
        ++exit[last];
        if (first == last) {
            bins[first].bounds.extend(r.bounds);
            return;
        }
        const Vec3 v[3] = {mesh.vertex(r.prim_id, 0), mesh.vertex(r.prim_id, 1), mesh.vertex(r.prim_id, 2)};
        // Where the triangle's edges cross the plane x[axis] = pos, strictly.
        auto crossings = [&](float pos) {
            AABB c = AABB::empty();
            for (int k = 0; k < 3; ++k) {
                const Vec3 a = v[k], b = v[k == 2 ? 0 : k + 1];
                if (!((a[axis] < pos && b[axis] > pos) || (a[axis] > pos && b[axis] < pos))) continue;
                Vec3 x = a + (b - a) * ((pos - a[axis]) / (b[axis] - a[axis]));
                x[axis] = pos;
                c.extend(x);
            }
            return c;
        };
        float left = r.bounds.lo[axis];
        AABB at_left = crossings(left);  // a clipped reference's triangle may reach past its box
        for (int i = first; i <= last; ++i) {
            const float right = i < last ? plane(i) : r.bounds.hi[axis];
            const AABB at_right = crossings(right);
            AABB piece = at_left;
            piece.extend(at_right);
            for (const Vec3& p : v)
                if (p[axis] >= left && p[axis] <= right) piece.extend(p);
            AABB clipped = r.bounds;
            clipped.lo[axis] = max_f(clipped.lo[axis], left);
            clipped.hi[axis] = min_f(clipped.hi[axis], right);
            clipped.lo = vmax(clipped.lo, piece.lo);
            clipped.hi = vmin(clipped.hi, piece.hi);
            if (!clipped.is_empty()) bins[i].bounds.extend(clipped);
            at_left = at_right;
            left = right;
        }
    }
};

}  // namespace bvhlab::accel
