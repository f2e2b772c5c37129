// SPDX-License-Identifier: MIT
// SparseTree compaction and the shared leaf policy.
#include "accel/builders/top_down.h"

#include <cmath>
#include <utility>

#include "accel/core/check.h"
#include "accel/core/sah.h"

namespace bvhlab::accel {

BuildTree SparseTree::compact(std::vector<uint32_t> prim_ids) const {
    BuildTree tree;
    tree.prim_indices = std::move(prim_ids);
    if (nodes_.empty()) return tree;
    tree.nodes.reserve(nodes_.size());
    tree.nodes.push_back(nodes_[0]);
    // (sparse slot, dense index) pairs; the right child is pushed first so the left subtree
    // is laid out first, which keeps a node's near child close in memory.
    std::vector<std::pair<size_t, uint32_t>> stack{{0, 0}};
    while (!stack.empty()) {
        auto [slot, dense] = stack.back();
        stack.pop_back();
        const BuildNode& n = nodes_[slot];
        if (n.is_leaf()) {
            tree.nodes[dense] = n;
            continue;
        }
        auto left = uint32_t(tree.nodes.size());
        tree.nodes.resize(tree.nodes.size() + 2);
        tree.nodes[dense] = {n.bounds, left, 0};
        stack.push_back({n.first_index, left + 1});
        stack.push_back({left_slot(uint32_t(slot)), left});
    }
    return tree;
}

SplitDecision decide_split(const BuildConfig& c, uint32_t count, uint32_t depth, float best_split_cost) {
    BVHLAB_CHECK(c.max_leaf_size >= 1 && c.min_leaf_size <= c.max_leaf_size,
                 "leaf size limits must satisfy 1 <= max_leaf_size and min_leaf_size <= max_leaf_size");
    if (count <= c.min_leaf_size) return SplitDecision::kLeaf;
    // Median splits halve the count, so this many more levels always suffice to reach leaves.
    const double needed = std::ceil(std::log2(std::max(1.0, double(count) / c.max_leaf_size)));
    if (double(depth) + needed + 1.0 >= double(c.max_depth)) {
        return count <= c.max_leaf_size ? SplitDecision::kLeaf : SplitDecision::kMedian;
    }
    const bool has_split = std::isfinite(best_split_cost);
    if (count <= c.max_leaf_size && (!has_split || sah_leaf_cost(c, count) <= best_split_cost)) {
        return SplitDecision::kLeaf;
    }
    return has_split ? SplitDecision::kSplit : SplitDecision::kMedian;
}

}  // namespace bvhlab::accel
