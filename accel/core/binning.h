// SPDX-License-Identifier: MIT
// Centroid binning for the binned SAH builder (Wald 2007, "On fast construction of SAH-based
// bounding volume hierarchies"). Shared by every builder that bins.
#pragma once

#include <algorithm>
#include <cfloat>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

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

/// Four floats in one SSE register, through the GCC/Clang vector extension (minps/maxps on
/// x86-64, no intrinsics). Binning and partition extend boxes with one min and one max per
/// corner instead of three of each; compare-and-select keeps vmin's NaN rule (the second
/// argument wins), so every bound and bin index equals the scalar code's.
using F4 = float __attribute__((vector_size(16)));
using I4 = int32_t __attribute__((vector_size(16)));

inline F4 f4_min(F4 a, F4 b) { return a < b ? a : b; }
inline F4 f4_max(F4 a, F4 b) { return a > b ? a : b; }
inline F4 f4(Vec3 v) { return F4{v.x, v.y, v.z, 0.0f}; }
inline Vec3 vec3(F4 v) { return {v[0], v[1], v[2]}; }

/// A reference's corners as F4 with lane 3 zero. Each is one 16-byte load (lo is followed by
/// hi.x, hi by prim_id, so the load stays inside the reference) and one AND: the id's bits
/// would be a denormal float, which costs a microcode assist in arithmetic.
inline void load_corners(const PrimRef& r, F4& lo, F4& hi) {
    static_assert(offsetof(PrimRef, bounds) == 0 && offsetof(PrimRef, prim_id) == 24, "PrimRef layout");
    const I4 mask = {-1, -1, -1, 0};
    I4 a, b;
    std::memcpy(&a, &r.bounds.lo, 16);
    std::memcpy(&b, &r.bounds.hi, 16);
    lo = F4(a & mask);
    hi = F4(b & mask);
}

/// A bin in F4 form, as binning accumulates it; to_bin() gives the Bin the sweep reads.
struct WideBin {
    F4 lo, hi;
    uint32_t count;

    static WideBin empty() { return {F4{FLT_MAX, FLT_MAX, FLT_MAX, 0.0f}, F4{-FLT_MAX, -FLT_MAX, -FLT_MAX, 0.0f}, 0}; }
    Bin to_bin() const { return {{vec3(lo), vec3(hi)}, count}; }
};

/// Object binning: adds each of `count` references to the bin of its centroid on every axis.
/// `bins` holds 3 * map.num_bins bins, axis-major. The centroid and the bin index are computed
/// with the same float operations, in the same order, as BinMapping::bin (one cvttps2dq for
/// three axes), so the bins are those of the scalar code. Measured: see experiments/NOTES.md,
/// session 15 (binning 20% of a 1M-triangle build before).
inline void bin_centroids(const PrimRef* refs, size_t count, const BinMapping& map, WideBin* bins) {
    const int nb = map.num_bins;
    const F4 origin = f4(map.origin), scale = f4(map.scale);
    const I4 last = {nb - 1, nb - 1, nb - 1, 0};
    for (size_t i = 0; i < count; ++i) {
        F4 lo, hi;
        load_corners(refs[i], lo, hi);
        const F4 c = (lo + hi) * 0.5f;
        I4 idx = __builtin_convertvector((c - origin) * scale, I4);
        idx = idx < 0 ? I4{0, 0, 0, 0} : idx;
        idx = idx > last ? last : idx;
        for (int a = 0; a < 3; ++a) {
            WideBin& b = bins[a * nb + idx[a]];
            b.lo = f4_min(b.lo, lo);
            b.hi = f4_max(b.hi, hi);
            ++b.count;
        }
    }
}

/// The same for bins in AABB form (the SBVH's object bins): converts, bins, converts back.
inline void bin_centroids(const PrimRef* refs, size_t count, const BinMapping& map, Bin* bins) {
    std::vector<WideBin> wide(3 * size_t(map.num_bins));
    for (size_t i = 0; i < wide.size(); ++i) wide[i] = {f4(bins[i].bounds.lo), f4(bins[i].bounds.hi), bins[i].count};
    bin_centroids(refs, count, map, wide.data());
    for (size_t i = 0; i < wide.size(); ++i) bins[i] = wide[i].to_bin();
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
