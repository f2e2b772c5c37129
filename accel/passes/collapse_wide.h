// SPDX-License-Identifier: MIT
// BuildTree -> 8-wide tree: the collapse pass of Ylitie, Karras & Laine ("Efficient incoherent
// ray traversal on GPUs through compressed wide BVHs", HPG 2017, section 3.1), usable after
// every BVH builder, and a greedy collapse beside it for comparison.
#pragma once

#include <cstdint>
#include <vector>

#include "accel/core/aabb.h"
#include "accel/core/build_tree.h"
#include "scene/mesh.h"

namespace bvhlab::accel {

/// Children of a wide node, and triangles of a wide leaf.
constexpr uint32_t kWideArity = 8;
constexpr uint32_t kWideMaxLeafSize = 3;

/// One child slot: an interior wide node (count == 0, index = its node) or a leaf of 1..3
/// triangles (index = its first entry in WideTree::prim_indices).
struct WideChild {
    AABB box;
    uint32_t index = 0;
    uint32_t count = 0;

    bool is_leaf() const { return count != 0; }
};

struct WideNode {
    AABB bounds;
    uint32_t child_count = 0;  ///< 1..8 (1 only for a root whose whole scene is one leaf)
    WideChild child[kWideArity];
};

/// Node 0 is the root. Every triangle reference of the binary tree appears in exactly one
/// leaf (an SBVH's duplicated references stay duplicated).
struct WideTree {
    std::vector<WideNode> nodes;
    std::vector<uint32_t> prim_indices;
    uint32_t depth = 0;  ///< wide nodes on the longest root-to-leaf path
};

enum class CollapseMethod {
    kSahOptimal,  ///< Ylitie et al.'s dynamic programme: the least wide-SAH cost over all collapses
    kGreedy,      ///< open the child with the largest area until 8 children
};

/// The wide SAH cost model: c_node per node visited, c_prim per triangle tested (the paper's
/// 1 and 0.3).
struct WideCost {
    float node = 1.0f;
    float prim = 0.3f;
};

/// Collapses a binary tree over `mesh` (leaves of any size: larger than 3 are first split at
/// their centroid median). The result is at most as deep as the binary tree plus the splits.
WideTree collapse_to_wide(const BuildTree& tree, const scene::TriangleMesh& mesh, CollapseMethod method,
                          WideCost cost = {});

struct WideStats {
    size_t nodes = 0, leaves = 0, references = 0;
    double mean_children = 0.0;  ///< child slots used per node
    double sah = 0.0;            ///< wide SAH under the cost model, relative to the root's area
    uint32_t depth = 0;
};

WideStats compute_wide_stats(const WideTree& tree, WideCost cost = {});

/// "" when `tree` is a valid wide tree over `triangle_count` triangles: every node reached
/// once, 1..8 children, leaves of 1..3 triangles with ids in range, every child box inside
/// its node's bounds, every reference of `binary_refs` (the binary tree's prim_indices, as a
/// multiset) kept. Otherwise the first problem found.
std::string validate_wide(const WideTree& tree, size_t triangle_count, const std::vector<uint32_t>& binary_refs);

}  // namespace bvhlab::accel
