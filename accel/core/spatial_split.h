// SPDX-License-Identifier: MIT
// Spatial-split binning (Stich, Friedrich & Dietrich 2009, "Spatial splits in bounding volume
// hierarchies"): references are chopped at bin boundaries by clipping their triangle, so each
// bin holds the exact bounds of the pieces inside it.
#pragma once

#include <cstdint>

#include "accel/core/binning.h"
#include "accel/core/clip.h"
#include "accel/core/prim_ref.h"

namespace bvhlab::accel {

/// The part of `box` on one side of the plane x[axis] = pos.
inline AABB clamp_box(AABB box, int axis, float pos, bool keep_left) {
    if (keep_left) box.hi[axis] = min_f(box.hi[axis], pos);
    else box.lo[axis] = max_f(box.lo[axis], pos);
    return box;
}

/// Exact bounds of the part of triangle `tri` inside `box` (empty if none).
inline AABB clipped_bounds(const TriangleMesh& mesh, uint32_t tri, const AABB& box) {
    return clip_triangle(mesh.vertex(tri, 0), mesh.vertex(tri, 1), mesh.vertex(tri, 2), box).bounds;
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

    /// Adds one reference, chopping it at every bin boundary it crosses.
    void add(const TriangleMesh& mesh, const PrimRef& r) {
        const int first = bin_of(r.bounds.lo[axis]), last = bin_of(r.bounds.hi[axis]);
        ++entry[first];
        ++exit[last];
        if (first == last) {
            bins[first].bounds.extend(r.bounds);
            return;
        }
        for (int i = first; i <= last; ++i) {
            AABB slab = r.bounds;
            if (i > first) slab.lo[axis] = max_f(slab.lo[axis], lo + width * float(i));
            if (i < last) slab.hi[axis] = min_f(slab.hi[axis], plane(i));
            bins[i].bounds.extend(clipped_bounds(mesh, r.prim_id, slab));
        }
    }
};

}  // namespace bvhlab::accel
