// SPDX-License-Identifier: MIT
// Surface-area-heuristic cost terms (Goldsmith & Salmon 1987, MacDonald & Booth 1990).
#pragma once

#include <cstdint>

#include "accel/core/build_tree.h"

namespace bvhlab::accel {

/// Cost of a split relative to the parent: Ct + Ci * (A_L N_L + A_R N_R) / A_P.
/// Areas may be half-areas; only their ratio matters.
inline float sah_split_cost(const BuildConfig& c, float parent_area, float left_area, uint64_t left_count,
                            float right_area, uint64_t right_count) {
    float inv = parent_area > 0.0f ? 1.0f / parent_area : 0.0f;
    return c.traversal_cost +
           c.intersection_cost * (left_area * float(left_count) + right_area * float(right_count)) * inv;
}

/// Cost of making a node with `count` primitives a leaf, in the same units.
inline float sah_leaf_cost(const BuildConfig& c, uint64_t count) { return c.intersection_cost * float(count); }

}  // namespace bvhlab::accel
