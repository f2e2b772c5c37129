// SPDX-License-Identifier: MIT
// A walk over a kd-tree's nodes with their cells, for its figures and its structural check.
#pragma once

#include <cstdint>
#include <vector>

#include "accel/core/aabb.h"
#include "accel/layouts/kd_node.h"

namespace bvhlab::accel {

/// Visits every node with its cell and depth (children after their parent): visit(index, node,
/// cell, depth) returns whether to descend.
template <typename F>
void walk_kd_cells(const KdTree& tree, F&& visit) {
    struct Item {
        uint32_t node;
        AABB cell;
        uint32_t depth;
    };
    std::vector<Item> stack{{0, tree.bounds, 0}};
    while (!stack.empty()) {
        const Item it = stack.back();
        stack.pop_back();
        const KdNode& n = tree.nodes[it.node];
        if (!visit(it.node, n, it.cell, it.depth) || n.is_leaf()) continue;
        AABB l = it.cell, r = it.cell;
        l.hi[int(n.axis())] = n.split();
        r.lo[int(n.axis())] = n.split();
        stack.push_back({n.child(), l, it.depth + 1});
        stack.push_back({n.child() + 1, r, it.depth + 1});
    }
}

}  // namespace bvhlab::accel
