// SPDX-License-Identifier: MIT
// The kd-tree builder's output before its final layout: the few nodes above the fragments,
// built in parallel, and the fragments, subtrees built by one thread each; flatten() joins
// them into one KdTree. Internal to the builder (not installed).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "accel/core/aabb.h"
#include "accel/layouts/kd_node.h"

namespace bvhlab::accel::kd {

/// A subtree built by one thread, in the final layout (children of a node side by side) but
/// with fragment-local node and triangle-list indices; node 0 is its root.
struct Fragment {
    std::vector<KdNode> nodes;
    std::vector<uint32_t> prims;
};

/// A node above the fragments: either a split with two children or a fragment.
struct TopNode {
    uint32_t axis = 3;
    float split = 0.0f;
    std::unique_ptr<TopNode> child[2];
    Fragment frag;
};

/// The final layout: the top nodes in depth-first order, each fragment appended whole with its
/// indices moved to their final place. Throws bvhlab::Error when the tree outgrows KdNode's
/// indices.
KdTree flatten(const TopNode& root, const AABB& bounds);

}  // namespace bvhlab::accel::kd
