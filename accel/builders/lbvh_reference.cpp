// SPDX-License-Identifier: MIT
#include "accel/builders/lbvh_reference.h"

#include <algorithm>
#include <limits>
#include <numeric>
#include <string>
#include <utility>

#include "accel/core/check.h"
#include "accel/core/morton.h"

namespace bvhlab::accel {

namespace {

/// The radix tree bottom-up, as the GPU climbs it (morton::radix_parent): from each leaf in
/// turn, the first of two siblings to arrive at their parent leaves its outer key there and
/// stops; the second boxes the parent (when h has boxes) and goes on (the GPU's atomic
/// exchanges, in one thread).
void emit_hierarchy(RawHierarchy& h) {
    const uint32_t n = uint32_t(h.keys.size());
    h.left.resize(n - 1);
    h.right.resize(n - 1);
    std::vector<uint32_t> outer(n - 1, ~0u);
    for (uint32_t k = 0; k < n; ++k) {
        uint32_t node = k, left = k, right = k;
        for (;;) {
            if (left == 0 && right == n - 1) {
                h.root = node;
                break;
            }
            const morton::RadixParent p = morton::radix_parent(h.keys.data(), n, left, right);
            (p.left_child ? h.left : h.right)[p.split] = node;
            uint32_t& o = outer[p.split];
            if (o == ~0u) {
                o = p.left_child ? left : right;
                break;
            }
            (p.left_child ? right : left) = o;
            node = n + p.split;
            if (!h.boxes.empty()) h.boxes[node] = merge(h.boxes[h.left[p.split]], h.boxes[h.right[p.split]]);
        }
    }
}

/// The leaves in Morton order: keys, sorted ids and the leaves' boxes (boxes sized for 2n - 1
/// nodes). The first step of every GPU builder.
RawHierarchy morton_order(const scene::TriangleMesh& mesh, int morton_bits) {
    if (morton_bits != 30 && morton_bits != 60)
        throw Error("morton_bits " + std::to_string(morton_bits) + " is neither 30 nor 60");
    const size_t n = mesh.triangle_count();
    if (n == 0) throw Error("the mesh has no triangles to build a structure over");
    RawHierarchy h;
    h.boxes.resize(2 * n - 1);
    std::vector<AABB> tri(n);
    AABB centres = AABB::empty();
    for (size_t t = 0; t < n; ++t) {
        tri[t] = mesh.triangle_bounds(t);
        centres.extend(tri[t].center());
    }
    const uint32_t cells = morton::cells_per_axis(morton_bits);
    const Vec3 scale{morton::axis_scale(centres.lo.x, centres.hi.x, cells),
                     morton::axis_scale(centres.lo.y, centres.hi.y, cells),
                     morton::axis_scale(centres.lo.z, centres.hi.z, cells)};
    std::vector<uint64_t> codes(n);
    for (size_t t = 0; t < n; ++t)
        codes[t] = morton_bits == 60 ? morton::code60(tri[t].center(), centres.lo, scale)
                                     : morton::code30(tri[t].center(), centres.lo, scale);
    h.sorted_ids.resize(n);
    std::iota(h.sorted_ids.begin(), h.sorted_ids.end(), 0u);
    // The GPU's radix sort is stable: equal keys keep the order of their triangle ids.
    std::stable_sort(h.sorted_ids.begin(), h.sorted_ids.end(),
                     [&](uint32_t a, uint32_t b) { return codes[a] < codes[b]; });
    h.keys.resize(n);
    for (size_t k = 0; k < n; ++k) {
        h.keys[k] = codes[h.sorted_ids[k]];
        h.boxes[k] = tri[h.sorted_ids[k]];
    }
    return h;
}

}  // namespace

RawHierarchy lbvh_reference(const scene::TriangleMesh& mesh, int morton_bits) {
    RawHierarchy h = morton_order(mesh, morton_bits);
    if (h.keys.size() > 1) emit_hierarchy(h);  // else the root is leaf 0
    return h;
}

RawHierarchy radix_tree(const std::vector<uint64_t>& keys) {
    if (keys.size() < 2 || !std::is_sorted(keys.begin(), keys.end()))
        throw Error("a radix tree needs at least two sorted keys");
    RawHierarchy h;
    h.keys = keys;
    emit_hierarchy(h);
    return h;
}

RawHierarchy ploc_reference(const scene::TriangleMesh& mesh, int morton_bits, int radius) {
    if (radius < 1 || radius > 16) throw Error("PLOC's radius " + std::to_string(radius) + " is outside [1, 16]");
    RawHierarchy h = morton_order(mesh, morton_bits);
    const uint32_t n = uint32_t(h.keys.size());
    h.left.reserve(n - 1);
    h.right.reserve(n - 1);
    std::vector<uint32_t> clusters(n), next, nn;
    std::iota(clusters.begin(), clusters.end(), 0u);
    uint32_t node = n;
    while (clusters.size() > 1) {
        const size_t m = clusters.size(), r = size_t(radius);
        nn.assign(m, 0);
        for (size_t i = 0; i < m; ++i) {
            float best = std::numeric_limits<float>::infinity();
            const AABB& b = h.boxes[clusters[i]];
            for (size_t j = i > r ? i - r : 0; j <= std::min(i + r, m - 1); ++j) {
                if (j == i) continue;
                const float a = merge(b, h.boxes[clusters[j]]).half_area();
                if (a < best) {  // on equal areas the lower place
                    best = a;
                    nn[i] = uint32_t(j);
                }
            }
        }
        next.clear();
        for (size_t i = 0; i < m; ++i) {
            const size_t j = nn[i];
            if (nn[j] != i) {
                next.push_back(clusters[i]);
            } else if (i < j) {
                h.left.push_back(clusters[i]);
                h.right.push_back(clusters[j]);
                h.boxes[node] = merge(h.boxes[clusters[i]], h.boxes[clusters[j]]);
                next.push_back(node++);
            }
        }
        clusters.swap(next);
    }
    h.root = clusters[0];
    return h;
}

BuildTree tree_from_hierarchy(const RawHierarchy& h, const BuildConfig& config) {
    const uint32_t n = uint32_t(h.sorted_ids.size());
    BVHLAB_CHECK(n > 0 && h.boxes.size() == 2 * size_t(n) - 1 && h.left.size() + 1 == n,
                 "a hierarchy of n leaves has n - 1 nodes");
    // Bottom-up (children before parents, by a depth-first walk): triangles and SAH cost of
    // every node, and whether its subtree becomes one leaf.
    const size_t total = h.boxes.size();
    std::vector<uint32_t> count(total, 1);
    std::vector<float> cost(total);
    std::vector<uint8_t> leaf(total, 1);
    std::vector<std::pair<uint32_t, bool>> stack{{h.root, false}};
    while (!stack.empty()) {
        const auto [x, expanded] = stack.back();
        stack.pop_back();
        const float area = h.boxes[x].half_area();
        if (x < n) {
            cost[x] = config.intersection_cost * area;
        } else if (!expanded) {
            stack.push_back({x, true});
            stack.push_back({h.right[x - n], false});
            stack.push_back({h.left[x - n], false});
        } else {
            const uint32_t a = h.left[x - n], b = h.right[x - n];
            count[x] = count[a] + count[b];
            const float inner = config.traversal_cost * area + cost[a] + cost[b];
            const float as_leaf = config.intersection_cost * float(count[x]) * area;
            leaf[x] = count[x] <= config.min_leaf_size || (count[x] <= config.max_leaf_size && as_leaf <= inner);
            cost[x] = leaf[x] ? as_leaf : inner;
        }
    }
    // Top-down: a node's children at two adjacent slots; a leaf's triangles left to right.
    BuildTree tree;
    tree.nodes.push_back({h.boxes[h.root], 0, 0});
    std::vector<std::pair<uint32_t, uint32_t>> todo{{h.root, 0}};  // hierarchy node, slot
    std::vector<uint32_t> below;
    while (!todo.empty()) {
        const auto [x, slot] = todo.back();
        todo.pop_back();
        if (leaf[x]) {
            tree.nodes[slot].first_index = uint32_t(tree.prim_indices.size());
            tree.nodes[slot].prim_count = count[x];
            below.assign(1, x);
            while (!below.empty()) {
                const uint32_t y = below.back();
                below.pop_back();
                if (y < n) {
                    tree.prim_indices.push_back(h.sorted_ids[y]);
                } else {
                    below.push_back(h.right[y - n]);
                    below.push_back(h.left[y - n]);
                }
            }
            continue;
        }
        const uint32_t first = uint32_t(tree.nodes.size());
        tree.nodes[slot].first_index = first;
        const uint32_t a = h.left[x - n], b = h.right[x - n];
        tree.nodes.push_back({h.boxes[a], 0, 0});
        tree.nodes.push_back({h.boxes[b], 0, 0});
        todo.push_back({b, first + 1});
        todo.push_back({a, first});
    }
    return tree;
}

}  // namespace bvhlab::accel
