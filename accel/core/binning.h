// SPDX-License-Identifier: MIT
// Centroid binning for the binned SAH builder (Wald 2007, "On fast construction of SAH-based
// bounding volume hierarchies"). Shared by every builder that bins.
#pragma once

#include <algorithm>
#include <cstdint>

#include "accel/core/aabb.h"

namespace bvhlab::accel {

/// Maps a centroid coordinate to one of `num_bins` equal-width bins over the centroid bounds.
struct BinMapping {
    Vec3 origin;  ///< lower corner of the centroid bounds
    Vec3 scale;   ///< bins per unit length along each axis (0 on flat axes)
    int num_bins;

    BinMapping(const AABB& centroid_bounds, int bins) : origin(centroid_bounds.lo), num_bins(bins) {
        Vec3 e = centroid_bounds.extent();
        // Slightly fewer than num_bins per extent so the maximum centroid lands in the last bin.
        const float k = float(bins) * (1.0f - 1e-6f);
        for (int a = 0; a < 3; ++a) scale[a] = e[a] > 0.0f ? k / e[a] : 0.0f;
    }
    /// Bin index of coordinate `c` on `axis`, clamped to [0, num_bins).
    int bin(float c, int axis) const {
        int i = int((c - origin[axis]) * scale[axis]);
        return std::min(std::max(i, 0), num_bins - 1);
    }
    bool splittable(int axis) const { return scale[axis] > 0.0f; }
};

/// Bounds and reference count of one bin. Trivially constructible so that fixed arrays of
/// bins cost nothing until reset; start each bin from Bin::empty().
struct Bin {
    AABB bounds;
    uint32_t count;

    static Bin empty() { return {AABB::empty(), 0}; }
};

}  // namespace bvhlab::accel
