// SPDX-License-Identifier: MIT
// Centroid binning for the binned SAH builder (Wald 2007, "On fast construction of SAH-based
// bounding volume hierarchies"). Shared by every builder that bins.
#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>

#include "accel/core/aabb.h"
#include "accel/core/prim_ref.h"

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

constexpr int kMaxBins = 256;

/// Best plane between the bins of one axis, ranked by A_L N_L + A_R N_R (half areas); the
/// SAH cost needs only one division by the parent's area, for the winner.
struct BinSweep {
    float weight = std::numeric_limits<float>::infinity();
    int bin = -1;  ///< references in bins <= bin go left; -1 when nothing separates them
};

/// Sweeps `count` bins once from each side (count <= kMaxBins). A bin's bounds are whatever
/// the caller accumulated: whole references for object splits, clipped pieces for spatial
/// splits, where `left_count` and `right_count` (entries and exits) replace Bin::count.
inline BinSweep sweep_bins(const Bin* bins, int count, const uint32_t* left_count = nullptr,
                           const uint32_t* right_count = nullptr) {
    float right_area[kMaxBins];
    uint32_t right_n[kMaxBins];
    AABB acc = AABB::empty();
    uint32_t n = 0;
    for (int i = count - 1; i > 0; --i) {
        acc.extend(bins[i].bounds);
        n += right_count ? right_count[i] : bins[i].count;
        right_area[i] = acc.half_area();
        right_n[i] = n;
    }
    BinSweep best;
    acc = AABB::empty();
    n = 0;
    for (int i = 0; i < count - 1; ++i) {
        acc.extend(bins[i].bounds);
        n += left_count ? left_count[i] : bins[i].count;
        if (n == 0 || right_n[i + 1] == 0) continue;
        const float w = acc.half_area() * float(n) + right_area[i + 1] * float(right_n[i + 1]);
        if (w < best.weight) best = {w, i};
    }
    return best;
}

/// Object binning: adds each of `count` references to the bin of its centroid on every axis.
/// `bins` holds 3 * map.num_bins bins, axis-major.
inline void bin_centroids(const PrimRef* refs, size_t count, const BinMapping& map, Bin* bins) {
    const int nb = map.num_bins;
    for (size_t i = 0; i < count; ++i) {
        const Vec3 c = refs[i].centroid();
        for (int a = 0; a < 3; ++a) {
            Bin& b = bins[a * nb + map.bin(c[a], a)];
            b.bounds.extend(refs[i].bounds);
            ++b.count;
        }
    }
}

/// The best object split over every splittable axis of axis-major `bins`.
struct AxisSplit {
    float weight = std::numeric_limits<float>::infinity();  ///< A_L N_L + A_R N_R
    int axis = -1;                                          ///< -1: nothing separates the refs
    int bin = -1;                                           ///< references in bins <= bin go left
};

inline AxisSplit best_bin_split(const Bin* bins, const BinMapping& map) {
    AxisSplit best;
    for (int a = 0; a < 3; ++a) {
        if (!map.splittable(a)) continue;
        const BinSweep sw = sweep_bins(&bins[a * map.num_bins], map.num_bins);
        if (sw.weight < best.weight) best = {sw.weight, a, sw.bin};
    }
    return best;
}

}  // namespace bvhlab::accel
