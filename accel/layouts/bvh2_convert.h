// SPDX-License-Identifier: MIT
// BuildTree -> Bvh2: folds leaves into their parents' child slots and builds Woop triangles.
#pragma once

#include <string>

#include "accel/core/build_tree.h"
#include "accel/layouts/bvh2_node.h"
#include "scene/mesh.h"

namespace bvhlab::accel {

/// "" when leaves of at most `config.max_leaf_size` triangles fit the BVH2 layout, else one line
/// saying they do not (the layout's leaf holds at most Bvh2Node::kMaxLeafCount).
std::string bvh2_leaf_problem(const BuildConfig& config);

/// Converts any BuildTree over `mesh`. A tree whose root is a leaf gets a root node with that
/// leaf as child 0 and an empty child 1. Node 0 of the result is the root.
Bvh2 convert_to_bvh2(const BuildTree& tree, const scene::TriangleMesh& mesh);

/// The nodes, leaf references (tri_ids = the tree's prim_indices) and depth of the same
/// conversion, without triangles: for trees over other primitives (the two-level top level).
Bvh2 convert_bvh2_nodes(const BuildTree& tree);

/// The BuildTree of a BVH2 (the binary tree that a GPU builder writes straight into the layout):
/// node 0 the root, each interior node's two children adjacent (depth first), each leaf's
/// triangles those of its tri_ids range, renumbered depth first so that every subtree's
/// triangles are contiguous in prim_indices as a top-down builder leaves them (a GPU layout
/// need not place leaves in that order); the boxes are the layout's child boxes. Figures,
/// validation and structure files work on it.
BuildTree build_tree_from_bvh2(const Bvh2& bvh);

}  // namespace bvhlab::accel
