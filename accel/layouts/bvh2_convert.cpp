// SPDX-License-Identifier: MIT
#include "accel/layouts/bvh2_convert.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cfloat>
#include <string>
#include <utility>

#include "accel/core/check.h"

namespace bvhlab::accel {

WoopTriangle make_woop_triangle(Vec3 v0, Vec3 v1, Vec3 v2) {
    WoopTriangle w;
    BVHLAB_CHECK(woop_map(v0, v1, v2, w), "Woop transform of a zero-area triangle");
    return w;
}

std::string bvh2_leaf_problem(const BuildConfig& config) {
    if (config.max_leaf_size <= Bvh2Node::kMaxLeafCount) return "";
    return "max_leaf " + std::to_string(config.max_leaf_size) +
           " does not fit the bvh2 layout, whose leaves hold at most " + std::to_string(Bvh2Node::kMaxLeafCount) +
           " triangles (the cwbvh layout takes up to 64)";
}

Bvh2 convert_to_bvh2(const BuildTree& tree, const scene::TriangleMesh& mesh) {
    Bvh2 out = convert_bvh2_nodes(tree);
    out.tris.resize(tree.prim_indices.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, out.tris.size(), 4096), [&](const auto& r) {
        for (size_t k = r.begin(); k < r.end(); ++k) {
            uint32_t t = tree.prim_indices[k];
            out.tris[k] = make_woop_triangle(mesh.vertex(t, 0), mesh.vertex(t, 1), mesh.vertex(t, 2));
        }
    });
    return out;
}

Bvh2 convert_bvh2_nodes(const BuildTree& tree) {
    BVHLAB_CHECK(!tree.empty(), "cannot convert an empty BuildTree");
    Bvh2 out;
    // Interior BuildTree nodes keep their relative order; map each to its Bvh2 index.
    std::vector<int32_t> index(tree.nodes.size(), -1);
    int32_t next = 0;
    for (size_t i = 0; i < tree.nodes.size(); ++i)
        if (!tree.nodes[i].is_leaf()) index[i] = next++;
    const bool root_leaf = tree.nodes[0].is_leaf();
    out.nodes.resize(root_leaf ? 1 : size_t(next));
    out.tri_ids = tree.prim_indices;
    auto fill_child = [&](Bvh2Node& n, int slot, const BuildNode& c, size_t ci) {
        n.set_child_box(slot, c.bounds);
        if (c.is_leaf()) {
            if (c.prim_count > Bvh2Node::kMaxLeafCount)
                throw Error("a leaf of " + std::to_string(c.prim_count) +
                            " triangles does not fit the BVH2 layout (at most " +
                            std::to_string(Bvh2Node::kMaxLeafCount) + ")");
            if (c.first_index > Bvh2Node::kMaxLeafFirst)
                throw Error("the BVH2 layout holds at most " + std::to_string(Bvh2Node::kMaxLeafFirst + 1) +
                            " triangle references; this tree has " + std::to_string(tree.prim_indices.size()));
            n.child[slot] = Bvh2Node::leaf_ref(c.first_index, c.prim_count);
        } else {
            n.child[slot] = index[ci];
        }
        n.reserved[slot] = 0;
    };
    if (root_leaf) {
        // A root that is a leaf: both slots name it, the second behind an empty box. An empty
        // (inverted) box still passes the slab test, so its triangles may be tested twice,
        // which gives the same answer.
        Bvh2Node& n = out.nodes[0];
        fill_child(n, 0, tree.nodes[0], 0);
        fill_child(n, 1, tree.nodes[0], 0);
        n.set_child_box(1, AABB::empty());
        out.depth = 1;
        return out;
    }
    for (size_t i = 0; i < tree.nodes.size(); ++i) {
        const BuildNode& b = tree.nodes[i];
        if (b.is_leaf()) continue;
        Bvh2Node& n = out.nodes[size_t(index[i])];
        fill_child(n, 0, tree.nodes[b.first_index], b.first_index);
        fill_child(n, 1, tree.nodes[b.first_index + 1], b.first_index + 1);
    }
    // Depth in interior nodes, by an explicit walk (children may precede parents after
    // reinsertion, so no single pass over the array gives it).
    std::vector<std::pair<int32_t, uint32_t>> todo{{0, 1}};
    while (!todo.empty()) {
        const auto [node, depth] = todo.back();
        todo.pop_back();
        out.depth = std::max(out.depth, depth);
        for (int32_t c : out.nodes[size_t(node)].child)
            if (c >= 0) todo.push_back({c, depth + 1});
    }
    return out;
}

BuildTree build_tree_from_bvh2(const Bvh2& bvh) {
    BVHLAB_CHECK(!bvh.nodes.empty(), "cannot convert an empty BVH2");
    BuildTree tree;
    tree.prim_indices.reserve(bvh.tri_ids.size());
    // Leaves are met depth first, left to right: their triangles are appended in that order.
    auto set = [&](size_t at, const Bvh2Node& n, int slot) {
        BuildNode& b = tree.nodes[at];
        b.bounds = n.child_box(slot);
        const int32_t c = n.child[slot];
        b.first_index = 0;
        b.prim_count = 0;
        if (c >= 0) return;
        b.first_index = uint32_t(tree.prim_indices.size());
        b.prim_count = Bvh2Node::leaf_count(c);
        const uint32_t first = Bvh2Node::leaf_first(c);
        tree.prim_indices.insert(tree.prim_indices.end(), bvh.tri_ids.begin() + first,
                                 bvh.tri_ids.begin() + first + b.prim_count);
    };
    const Bvh2Node& root = bvh.nodes[0];
    tree.nodes.resize(1);
    if (root.child[0] < 0 && root.child[1] == root.child[0]) {  // a root leaf (its second slot is empty)
        set(0, root, 0);
        return tree;
    }
    tree.nodes[0] = {merge(root.child_box(0), root.child_box(1)), 0, 0};
    std::vector<std::pair<int32_t, size_t>> todo{{0, 0}};  // layout node, its BuildTree node
    while (!todo.empty()) {
        const auto [k, at] = todo.back();
        todo.pop_back();
        const Bvh2Node& n = bvh.nodes[size_t(k)];
        const size_t first = tree.nodes.size();
        tree.nodes[at].first_index = uint32_t(first);
        tree.nodes.resize(first + 2);
        for (int slot = 0; slot < 2; ++slot) set(first + size_t(slot), n, slot);
        for (int slot = 1; slot >= 0; --slot)
            if (n.child[slot] >= 0) todo.push_back({n.child[slot], first + size_t(slot)});
    }
    return tree;
}

}  // namespace bvhlab::accel
