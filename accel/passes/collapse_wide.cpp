// SPDX-License-Identifier: MIT
#include "accel/passes/collapse_wide.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "accel/core/check.h"

namespace bvhlab::accel {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

/// Splits every leaf of more than kWideMaxLeafSize references at the median of their
/// centroids along the largest axis, until no leaf is larger. New nodes go at the end, in
/// sibling pairs, so the BuildTree invariants hold. Child boxes are the references'
/// triangle boxes clipped to the leaf's box (an SBVH leaf's box is already clipped).
BuildTree split_large_leaves(const BuildTree& in, const scene::TriangleMesh& mesh) {
    BuildTree t = in;
    std::vector<uint32_t> todo;
    for (uint32_t i = 0; i < t.nodes.size(); ++i)
        if (t.nodes[i].prim_count > kWideMaxLeafSize) todo.push_back(i);
    while (!todo.empty()) {
        const uint32_t n = todo.back();
        todo.pop_back();
        const BuildNode leaf = t.nodes[n];
        uint32_t* refs = t.prim_indices.data() + leaf.first_index;
        AABB centroids = AABB::empty();
        for (uint32_t k = 0; k < leaf.prim_count; ++k) centroids.extend(mesh.triangle_bounds(refs[k]).center());
        const int axis = centroids.largest_axis();
        const uint32_t half = leaf.prim_count / 2;
        std::nth_element(refs, refs + half, refs + leaf.prim_count, [&](uint32_t a, uint32_t b) {
            return mesh.triangle_bounds(a).center()[axis] < mesh.triangle_bounds(b).center()[axis];
        });
        const uint32_t first_child = uint32_t(t.nodes.size());
        for (int side = 0; side < 2; ++side) {
            BuildNode c;
            c.first_index = leaf.first_index + (side ? half : 0);
            c.prim_count = side ? leaf.prim_count - half : half;
            c.bounds = AABB::empty();
            for (uint32_t k = 0; k < c.prim_count; ++k)
                c.bounds.extend(mesh.triangle_bounds(t.prim_indices[c.first_index + k]));
            c.bounds = intersect(c.bounds, leaf.bounds);
            if (c.prim_count > kWideMaxLeafSize) todo.push_back(uint32_t(t.nodes.size()));
            t.nodes.push_back(c);
        }
        t.nodes[n].first_index = first_child;
        t.nodes[n].prim_count = 0;
    }
    return t;
}

/// What the dynamic programme chose for C(n, i), i = 1..8 slots.
enum : int8_t { kLeaf = -1, kInternal = -2, kFewer = -3 };

class Collapser {
public:
    Collapser(const BuildTree& t, CollapseMethod method, WideCost cost)
        : t_(t), method_(method), cost_(cost), count_(t.nodes.size()) {
        order_post();
        for (uint32_t n : post_) {
            const BuildNode& b = t_.nodes[n];
            count_[n] = b.is_leaf() ? b.prim_count : count_[b.first_index] + count_[b.first_index + 1];
        }
        if (method_ == CollapseMethod::kSahOptimal) solve();
    }

    WideTree run() {
        WideTree w;
        w.prim_indices.reserve(t_.prim_indices.size());
        const BuildNode& root = t_.nodes[0];
        if (root.is_leaf()) {  // the whole scene is one leaf: a root with one leaf child
            WideNode r;
            r.bounds = root.bounds;
            r.child_count = 1;
            r.child[0] = make_leaf(0, w);
            w.nodes.push_back(r);
            w.depth = 1;
            return w;
        }
        w.nodes.emplace_back();
        emit(0, 0, 1, w);
        return w;
    }

private:
    void order_post() {
        post_.reserve(t_.nodes.size());
        std::vector<std::pair<uint32_t, bool>> stack{{0u, false}};
        while (!stack.empty()) {
            auto [n, expanded] = stack.back();
            stack.pop_back();
            const BuildNode& b = t_.nodes[n];
            if (expanded || b.is_leaf()) {
                post_.push_back(n);
                continue;
            }
            stack.push_back({n, true});
            stack.push_back({b.first_index + 1, false});
            stack.push_back({b.first_index, false});
        }
    }

    float area(uint32_t n) const { return t_.nodes[n].bounds.half_area(); }

    /// C(n, i) and its choice for i = 1..8, children before parents (Ylitie et al., eq. 1-3).
    void solve() {
        const size_t n_nodes = t_.nodes.size();
        cost_tab_.assign(n_nodes * kWideArity, kInf);
        choice_.assign(n_nodes * kWideArity, kLeaf);
        split_.assign(n_nodes * kWideArity, 0);
        for (uint32_t n : post_) {
            const BuildNode& b = t_.nodes[n];
            float* c = &cost_tab_[size_t(n) * kWideArity];  // c[i - 1] = C(n, i)
            int8_t* ch = &choice_[size_t(n) * kWideArity];
            uint8_t* sp = &split_[size_t(n) * kWideArity];
            float dist[kWideArity + 1];  // dist[j] = the best split of j slots over the children
            std::fill(dist, dist + kWideArity + 1, kInf);
            if (!b.is_leaf()) {
                const float* cl = &cost_tab_[size_t(b.first_index) * kWideArity];
                const float* cr = &cost_tab_[size_t(b.first_index + 1) * kWideArity];
                for (uint32_t j = 2; j <= kWideArity; ++j)
                    for (uint32_t k = 1; k < j; ++k) {
                        const float v = cl[k - 1] + cr[j - k - 1];
                        if (v < dist[j]) {
                            dist[j] = v;
                            sp[j - 1] = uint8_t(k);
                        }
                    }
            }
            const float leaf = count_[n] <= kWideMaxLeafSize ? area(n) * float(count_[n]) * cost_.prim : kInf;
            const float internal = b.is_leaf() ? kInf : dist[kWideArity] + area(n) * cost_.node;
            c[0] = std::min(leaf, internal);
            ch[0] = leaf <= internal ? kLeaf : kInternal;
            for (uint32_t i = 2; i <= kWideArity; ++i) {
                if (dist[i] < c[i - 2]) {
                    c[i - 1] = dist[i];
                    ch[i - 1] = int8_t(i);  // distribute over the two children
                } else {
                    c[i - 1] = c[i - 2];
                    ch[i - 1] = kFewer;
                }
            }
        }
    }

    /// The binary nodes that fill `slots` child slots for subtree n, and whether each is a leaf.
    void gather(uint32_t n, uint32_t slots, std::vector<std::pair<uint32_t, bool>>& out) const {
        const int8_t* ch = &choice_[size_t(n) * kWideArity];
        while (slots > 1 && ch[slots - 1] == kFewer) --slots;
        if (slots == 1) {
            out.push_back({n, ch[0] == kLeaf});
            return;
        }
        const BuildNode& b = t_.nodes[n];
        const uint32_t k = split_[size_t(n) * kWideArity + slots - 1];
        gather(b.first_index, k, out);
        gather(b.first_index + 1, slots - k, out);
    }

    /// The children of the wide node for interior binary node n.
    std::vector<std::pair<uint32_t, bool>> children_of(uint32_t n) const {
        std::vector<std::pair<uint32_t, bool>> out;
        const BuildNode& b = t_.nodes[n];
        if (method_ == CollapseMethod::kSahOptimal) {
            const uint32_t k = split_[size_t(n) * kWideArity + kWideArity - 1];  // dist[8]'s split
            gather(b.first_index, k, out);
            gather(b.first_index + 1, kWideArity - k, out);
            return out;
        }
        // Greedy: open the child of largest area until 8; a subtree of at most 3 references
        // becomes a leaf and is never opened.
        auto is_leaf = [&](uint32_t c) { return count_[c] <= kWideMaxLeafSize; };
        out = {{b.first_index, is_leaf(b.first_index)}, {b.first_index + 1, is_leaf(b.first_index + 1)}};
        while (out.size() < kWideArity) {
            int best = -1;
            for (size_t i = 0; i < out.size(); ++i)
                if (!out[i].second && (best < 0 || area(out[i].first) > area(out[size_t(best)].first))) best = int(i);
            if (best < 0) break;
            const uint32_t c = out[size_t(best)].first;
            const uint32_t l = t_.nodes[c].first_index;
            out[size_t(best)] = {l, is_leaf(l)};
            out.push_back({l + 1, is_leaf(l + 1)});
        }
        return out;
    }

    /// A leaf child holding every reference under binary node n.
    WideChild make_leaf(uint32_t n, WideTree& w) const {
        WideChild c;
        c.box = t_.nodes[n].bounds;
        c.index = uint32_t(w.prim_indices.size());
        std::vector<uint32_t> stack{n};
        while (!stack.empty()) {
            const BuildNode& b = t_.nodes[stack.back()];
            stack.pop_back();
            if (b.is_leaf()) {
                w.prim_indices.insert(w.prim_indices.end(), t_.prim_indices.begin() + b.first_index,
                                      t_.prim_indices.begin() + b.first_index + b.prim_count);
            } else {
                stack.push_back(b.first_index + 1);
                stack.push_back(b.first_index);
            }
        }
        c.count = uint32_t(w.prim_indices.size()) - c.index;
        return c;
    }

    /// Fills wide node `wi` from interior binary node n, depth-first.
    void emit(uint32_t n, uint32_t wi, uint32_t depth, WideTree& w) {
        w.depth = std::max(w.depth, depth);
        const auto kids = children_of(n);
        BVHLAB_CHECK(kids.size() >= 2 && kids.size() <= kWideArity,
                     "collapse gave a node of " + std::to_string(kids.size()) + " children");
        w.nodes[wi].bounds = t_.nodes[n].bounds;
        w.nodes[wi].child_count = uint32_t(kids.size());
        for (size_t i = 0; i < kids.size(); ++i) {
            const auto [c, leaf] = kids[i];
            if (leaf) {
                w.nodes[wi].child[i] = make_leaf(c, w);
                continue;
            }
            const uint32_t ci = uint32_t(w.nodes.size());
            w.nodes.emplace_back();
            w.nodes[wi].child[i].box = t_.nodes[c].bounds;
            w.nodes[wi].child[i].index = ci;
            w.nodes[wi].child[i].count = 0;
            emit(c, ci, depth + 1, w);
        }
    }

    const BuildTree& t_;
    CollapseMethod method_;
    WideCost cost_;
    std::vector<uint32_t> count_;  // references under each binary node
    std::vector<uint32_t> post_;
    std::vector<float> cost_tab_;
    std::vector<int8_t> choice_;
    std::vector<uint8_t> split_;
};

}  // namespace

WideTree collapse_to_wide(const BuildTree& tree, const scene::TriangleMesh& mesh, CollapseMethod method,
                          WideCost cost) {
    BVHLAB_CHECK(!tree.empty(), "cannot collapse an empty BuildTree");
    const BuildTree split = split_large_leaves(tree, mesh);
    return Collapser(split, method, cost).run();
}

WideStats compute_wide_stats(const WideTree& w, WideCost cost) {
    WideStats s;
    s.nodes = w.nodes.size();
    s.depth = w.depth;
    s.references = w.prim_indices.size();
    if (w.nodes.empty()) return s;
    const double root = std::max(double(w.nodes[0].bounds.half_area()), 1e-30);
    size_t slots = 0;
    for (const WideNode& n : w.nodes) {
        slots += n.child_count;
        s.sah += cost.node * double(n.bounds.half_area()) / root;
        for (uint32_t i = 0; i < n.child_count; ++i)
            if (n.child[i].is_leaf()) {
                ++s.leaves;
                s.sah += cost.prim * double(n.child[i].count) * double(n.child[i].box.half_area()) / root;
            }
    }
    s.mean_children = double(slots) / double(s.nodes);
    return s;
}

std::string validate_wide(const WideTree& w, size_t triangle_count, const std::vector<uint32_t>& binary_refs) {
    if (w.nodes.empty()) return "no nodes";
    std::vector<uint8_t> seen(w.nodes.size(), 0);
    std::vector<uint32_t> refs;
    std::vector<std::pair<uint32_t, uint32_t>> stack{{0u, 1u}};
    seen[0] = 1;
    uint32_t depth = 0;
    while (!stack.empty()) {
        const auto [ni, d] = stack.back();
        stack.pop_back();
        depth = std::max(depth, d);
        const WideNode& n = w.nodes[ni];
        const std::string where = "node " + std::to_string(ni);
        if (n.child_count < 1 || n.child_count > kWideArity)
            return where + " has " + std::to_string(n.child_count) + " children";
        for (uint32_t i = 0; i < n.child_count; ++i) {
            const WideChild& c = n.child[i];
            if (!n.bounds.contains(c.box)) return where + ": child " + std::to_string(i) + " is outside its bounds";
            if (c.is_leaf()) {
                if (c.count > kWideMaxLeafSize) return where + ": a leaf of " + std::to_string(c.count) + " triangles";
                if (size_t(c.index) + c.count > w.prim_indices.size()) return where + ": leaf range out of bounds";
                for (uint32_t k = 0; k < c.count; ++k) {
                    const uint32_t id = w.prim_indices[c.index + k];
                    if (id >= triangle_count) return where + ": triangle id " + std::to_string(id) + " out of range";
                    refs.push_back(id);
                }
                continue;
            }
            if (c.index >= w.nodes.size()) return where + ": child node index out of range";
            if (seen[c.index]++) return "node " + std::to_string(c.index) + " is reached twice";
            const AABB& nb = w.nodes[c.index].bounds;
            if (!(c.box.contains(nb) && nb.contains(c.box)))
                return where + ": child " + std::to_string(i) + "'s box differs from its node's bounds";
            stack.push_back({c.index, d + 1});
        }
    }
    for (size_t i = 0; i < seen.size(); ++i)
        if (!seen[i]) return "node " + std::to_string(i) + " is unreachable";
    if (depth != w.depth) return "depth " + std::to_string(w.depth) + " recorded, " + std::to_string(depth) + " found";
    std::vector<uint32_t> want = binary_refs;
    std::sort(want.begin(), want.end());
    std::sort(refs.begin(), refs.end());
    if (refs != want) return "the leaves do not hold the binary tree's references";
    return "";
}

}  // namespace bvhlab::accel
