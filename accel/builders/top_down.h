// SPDX-License-Identifier: MIT
// Pieces every top-down builder shares: deterministic node slots for parallel recursion,
// the compaction into a BuildTree, and the leaf / forced-split policy.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "accel/core/build_tree.h"

namespace bvhlab::accel {

/// Node storage that parallel recursion can fill without atomics and with a deterministic
/// result. A subtree over n references rooted at slot s owns the slots [s, s + 2n - 1)
/// (a binary tree with non-empty leaves has at most 2n - 1 nodes). Splitting [b, e) at m puts
/// the left child at s + 1 and the right child at s + 2(m - b). An interior slot stores its
/// right child's slot in first_index; a leaf stores its reference range.
class SparseTree {
public:
    explicit SparseTree(size_t ref_count) : nodes_(ref_count == 0 ? 0 : 2 * ref_count - 1) {}

    static uint32_t left_slot(uint32_t slot) { return slot + 1; }
    static uint32_t right_slot(uint32_t slot, uint32_t b, uint32_t m) { return slot + 2 * (m - b); }

    void set_leaf(uint32_t slot, uint32_t b, uint32_t e, const AABB& bounds) { nodes_[slot] = {bounds, b, e - b}; }
    void set_interior(uint32_t slot, uint32_t b, uint32_t m, const AABB& bounds) {
        nodes_[slot] = {bounds, right_slot(slot, b, m), 0};
    }

    /// Depth-first compaction: siblings adjacent, left subtree first. `prim_ids` is the final
    /// order of the references' triangle ids.
    BuildTree compact(std::vector<uint32_t> prim_ids) const;

private:
    std::vector<BuildNode> nodes_;
};

/// What a builder does with a node once it knows its best split cost.
enum class SplitDecision { kLeaf, kSplit, kMedian };

/// The leaf policy both SAH builders use. `best_split_cost` is +inf when no split separates
/// the references. Forces a median split when SAH splits could push the tree past max_depth.
SplitDecision decide_split(const BuildConfig& c, uint32_t count, uint32_t depth, float best_split_cost);

/// Frees a pointer tree (nodes with `std::unique_ptr<Node> child[2]`) without recursion: the
/// recursive destructor could overflow the stack on a deep tree.
template <typename Node>
void destroy_iteratively(std::unique_ptr<Node> root) {
    std::vector<std::unique_ptr<Node>> drop;
    drop.push_back(std::move(root));
    while (!drop.empty()) {
        std::unique_ptr<Node> n = std::move(drop.back());
        drop.pop_back();
        for (auto& c : n->child)
            if (c) drop.push_back(std::move(c));
    }
}

}  // namespace bvhlab::accel
