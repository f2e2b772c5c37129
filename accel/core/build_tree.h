// SPDX-License-Identifier: MIT
// The intermediate binary tree that every builder returns and every pass and layout consumes.
#pragma once

#include <cstdint>
#include <vector>

#include "accel/core/aabb.h"

namespace bvhlab::accel {

class ProgressCounter;  // accel/core/progress.h

/// One node of a BuildTree, 32 bytes. An interior node has prim_count == 0 and its two
/// children at first_index and first_index + 1 (siblings are always adjacent). A leaf
/// references prim_indices[first_index .. first_index + prim_count).
struct BuildNode {
    AABB bounds;           // 24 bytes
    uint32_t first_index;  // 4 bytes: left child, or first entry in prim_indices
    uint32_t prim_count;   // 4 bytes: 0 for interior nodes; total 32 bytes

    bool is_leaf() const { return prim_count != 0; }
};
static_assert(sizeof(BuildNode) == 32, "BuildNode is 32 bytes");

/// Binary BVH in builder-neutral form. Node 0 is the root. prim_indices holds triangle ids;
/// an object-split builder references each triangle exactly once, a spatial-split builder
/// (SBVH) at least once. Owns all its data.
struct BuildTree {
    std::vector<BuildNode> nodes;
    std::vector<uint32_t> prim_indices;

    bool empty() const { return nodes.empty(); }
    size_t bytes() const { return nodes.size() * sizeof(BuildNode) + prim_indices.size() * sizeof(uint32_t); }
};

/// The deepest tree any builder makes (interior nodes on a root-to-leaf path), BVH or kd-tree.
/// The one constant behind every full traversal stack, CPU and GPU: the stacks are
/// static_assert-ed against it (bvh2_traverse.h, kd_traverse.h, cwbvh_traverse.h), and a tree
/// read from a file is measured, never trusted for its depth.
constexpr uint32_t kMaxTreeDepth = 64;

/// Settings every top-down builder shares. Builders nest their own Config deriving from it.
struct BuildConfig {
    float traversal_cost = 1.0f;         ///< Ct: cost of visiting an interior node
    float intersection_cost = 1.0f;      ///< Ci: cost of one triangle test
    uint32_t min_leaf_size = 1;          ///< nodes this small always become leaves
    uint32_t max_leaf_size = 8;          ///< nodes larger than this are always split
    uint32_t max_depth = kMaxTreeDepth;  ///< the traversal stacks are sized for this depth
    /// Not part of the tree's configuration: when set, each leaf adds its reference count here
    /// as it is made (run_builder reports the progress through it).
    ProgressCounter* progress = nullptr;
};

}  // namespace bvhlab::accel
