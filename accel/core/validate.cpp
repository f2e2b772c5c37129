// SPDX-License-Identifier: MIT
#include "accel/core/validate.h"

#include <vector>

#include "accel/core/kd_cells.h"

namespace bvhlab::accel {

std::string validate(const BuildTree& tree, const scene::TriangleMesh& mesh, const BuildConfig& config,
                     const ValidateOptions& options) {
    if (tree.nodes.empty()) return "tree has no nodes";
    const size_t nn = tree.nodes.size();
    std::vector<uint8_t> seen(nn, 0);
    std::vector<uint32_t> refs(mesh.triangle_count(), 0);
    std::vector<uint8_t> pos_used(tree.prim_indices.size(), 0);
    struct Item {
        uint32_t node, depth;
    };
    std::vector<Item> stack{{0, 0}};
    seen[0] = 1;
    while (!stack.empty()) {
        Item it = stack.back();
        stack.pop_back();
        const BuildNode& n = tree.nodes[it.node];
        const std::string where = "node " + std::to_string(it.node) + ": ";
        if (it.depth >= config.max_depth) return where + "depth exceeds max_depth";
        if (n.is_leaf()) {
            if (n.prim_count > config.max_leaf_size) return where + "leaf larger than max_leaf_size";
            if (size_t(n.first_index) + n.prim_count > tree.prim_indices.size())
                return where + "leaf range outside prim_indices";
            for (uint32_t k = n.first_index; k < n.first_index + n.prim_count; ++k) {
                if (pos_used[k]++) return where + "prim_indices position used by two leaves";
                uint32_t id = tree.prim_indices[k];
                if (id >= refs.size()) return where + "triangle id out of range";
                ++refs[id];
                const AABB tb = mesh.triangle_bounds(id);
                if (options.allow_duplicates ? !n.bounds.overlaps(tb) : !n.bounds.contains(tb))
                    return where + "leaf bounds do not hold triangle " + std::to_string(id);
            }
            continue;
        }
        if (size_t(n.first_index) + 1 >= nn || n.first_index == 0) return where + "child index out of range";
        for (uint32_t c = n.first_index; c <= n.first_index + 1; ++c) {
            if (seen[c]++) return where + "child " + std::to_string(c) + " reached twice";
            if (!n.bounds.contains(tree.nodes[c].bounds))
                return where + "child " + std::to_string(c) + " bounds outside the parent's";
            stack.push_back({c, it.depth + 1});
        }
    }
    for (size_t i = 0; i < nn; ++i)
        if (!seen[i]) return "node " + std::to_string(i) + " is unreachable";
    for (size_t k = 0; k < pos_used.size(); ++k)
        if (!pos_used[k]) return "prim_indices position " + std::to_string(k) + " is in no leaf";
    for (size_t t = 0; t < refs.size(); ++t) {
        if (refs[t] == 0) return "triangle " + std::to_string(t) + " is not referenced";
        if (refs[t] > 1 && !options.allow_duplicates)
            return "triangle " + std::to_string(t) + " is referenced " + std::to_string(refs[t]) + " times";
    }
    return {};
}

std::string validate_kd(const KdTree& tree, size_t triangles) {
    if (tree.nodes.empty()) return "kd-tree has no nodes";
    std::vector<uint8_t> seen(tree.nodes.size(), 0);
    std::string err;
    walk_kd_cells(tree, [&](uint32_t i, const KdNode& n, const AABB& cell, uint32_t) {
        const std::string where = "kd node " + std::to_string(i) + ": ";
        if (seen[i]++)
            err = where + "reached twice";
        else if (n.is_leaf() && size_t(n.first()) + n.count() > tree.prim_indices.size())
            err = where + "leaf range out of range";
        else if (!n.is_leaf() && size_t(n.child()) + 1 >= tree.nodes.size())
            err = where + "child out of range";
        else if (!n.is_leaf() && !(n.split() >= cell.lo[int(n.axis())] && n.split() <= cell.hi[int(n.axis())]))
            err = where + "split outside its cell";
        return err.empty();  // stop descending once something is wrong
    });
    if (!err.empty()) return err;
    for (size_t i = 0; i < seen.size(); ++i)
        if (!seen[i]) return "kd node " + std::to_string(i) + " is unreachable";
    for (uint32_t id : tree.prim_indices)
        if (id >= triangles) return "triangle id " + std::to_string(id) + " out of range";
    return {};
}

}  // namespace bvhlab::accel
