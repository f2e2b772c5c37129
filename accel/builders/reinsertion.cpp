// SPDX-License-Identifier: MIT
// Reinsertion: each pass takes every node, the largest first, cuts it out (its parent goes with
// it and its sibling takes the parent's place), and puts it back as the sibling of the node X
// that minimises the growth in interior area: A(X u N) plus, on every ancestor a of X,
// A(a u N) - A(a). Candidates X are visited best-first; a node whose ancestors' growth alone
// already reaches the best cost found prunes its whole subtree. Leaves never change, so the
// SAH changes only through interior areas, and putting N back where it was is always one of
// the candidates: no move makes the tree worse.
#include "accel/builders/reinsertion.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <vector>

#include "accel/core/check.h"

namespace bvhlab::accel {
namespace {

constexpr uint32_t kNone = ~0u;

/// The tree with parent links and free child links, so subtrees can move.
class MutableTree {
public:
    explicit MutableTree(const BuildTree& t)
        : box_(t.nodes.size()), parent_(t.nodes.size(), kNone), kid_(t.nodes.size()), height_(t.nodes.size(), 0) {
        for (size_t i = 0; i < t.nodes.size(); ++i) {
            const BuildNode& n = t.nodes[i];
            box_[i] = n.bounds;
            kid_[i] = {kNone, kNone};
            if (!n.is_leaf()) {
                kid_[i] = {n.first_index, n.first_index + 1};
                parent_[n.first_index] = parent_[n.first_index + 1] = uint32_t(i);
            }
        }
        // Children follow their parents in a BuildTree, so a reverse sweep sees kids first.
        for (size_t i = t.nodes.size(); i-- > 0;)
            if (!leaf(uint32_t(i))) update_height(uint32_t(i));
    }

    bool leaf(uint32_t n) const { return kid_[n][0] == kNone; }
    float area(uint32_t n) const { return box_[n].half_area(); }
    uint32_t root() const { return root_; }
    uint32_t parent(uint32_t n) const { return parent_[n]; }
    size_t size() const { return box_.size(); }

    double interior_area() const {
        double s = 0;
        for (size_t i = 0; i < box_.size(); ++i)
            if (!leaf(uint32_t(i))) s += box_[i].half_area();
        return s;
    }

    /// Search state of one thread.
    struct Entry {
        float induced;  ///< interior-area growth on the ancestors if n goes below this node
        uint32_t node, depth;
        bool operator<(const Entry& o) const { return induced > o.induced; }  // min-heap
    };
    using Heap = std::vector<Entry>;

    /// Cuts n (not `top` or a child of `top`) out of the subtree under `top`, then puts it
    /// back as the sibling of the node in that subtree where the interior area grows least,
    /// with no leaf deeper than max_depth (`top` is at depth top_depth). The subtree's leaf set
    /// stays the same, so nothing above `top` changes: threads may work on disjoint subtrees.
    /// Returns whether n moved.
    bool reinsert(uint32_t n, uint32_t top, uint32_t top_depth, uint32_t max_depth, Heap& heap) {
        const uint32_t p = parent_[n], g = parent_[p];
        const uint32_t s = kid_[p][0] == n ? kid_[p][1] : kid_[p][0];
        // Detach: the sibling takes the parent's place; p becomes free for the insertion.
        parent_[s] = g;
        kid_[g][kid_[g][0] == p ? 0 : 1] = s;
        refit(g, top);
        const uint32_t x = best_sibling(n, top, top_depth, max_depth, heap);
        BVHLAB_CHECK(x != kNone, "reinsertion found no place for a subtree");
        const uint32_t gx = parent_[x];
        kid_[p] = {x, n};
        parent_[x] = parent_[n] = p;
        parent_[p] = gx;
        kid_[gx][kid_[gx][0] == x ? 0 : 1] = p;
        refit(p, top);
        return x != s;
    }

    /// Preorder of the tree, each node's depth and subtree size (in nodes).
    void index(std::vector<uint32_t>& pre, std::vector<uint32_t>& depth, std::vector<uint32_t>& size) const {
        pre.clear();
        depth.assign(box_.size(), 0);
        size.assign(box_.size(), 1);
        std::vector<uint32_t> stack{root_};
        while (!stack.empty()) {
            const uint32_t n = stack.back();
            stack.pop_back();
            pre.push_back(n);
            if (leaf(n)) continue;
            for (int k = 1; k >= 0; --k) {
                depth[kid_[n][k]] = depth[n] + 1;
                stack.push_back(kid_[n][k]);
            }
        }
        for (size_t i = pre.size(); i-- > 0;) {
            const uint32_t n = pre[i];
            if (!leaf(n)) size[n] = 1 + size[kid_[n][0]] + size[kid_[n][1]];
        }
    }

    /// Recomputes the heights of the nodes with subtrees over `cut` nodes, bottom-up.
    void refresh_heights(const std::vector<uint32_t>& pre, const std::vector<uint32_t>& size, uint32_t cut) {
        for (size_t i = pre.size(); i-- > 0;) {
            const uint32_t n = pre[i];
            if (size[n] > cut) update_height(n);
        }
    }

    /// Depth-first BuildTree: siblings adjacent, each subtree's references contiguous.
    BuildTree flatten(const BuildTree& old) const {
        BuildTree t;
        t.nodes.reserve(size());
        t.prim_indices.reserve(old.prim_indices.size());
        t.nodes.push_back({});
        std::vector<std::pair<uint32_t, uint32_t>> stack{{root_, 0}};
        while (!stack.empty()) {
            const auto [n, slot] = stack.back();
            stack.pop_back();
            if (leaf(n)) {
                const BuildNode& o = old.nodes[n];
                t.nodes[slot] = {box_[n], uint32_t(t.prim_indices.size()), o.prim_count};
                t.prim_indices.insert(t.prim_indices.end(), old.prim_indices.begin() + o.first_index,
                                      old.prim_indices.begin() + o.first_index + o.prim_count);
                continue;
            }
            const auto k = uint32_t(t.nodes.size());
            t.nodes.resize(k + 2);
            t.nodes[slot] = {box_[n], k, 0};
            stack.push_back({kid_[n][1], k + 1});
            stack.push_back({kid_[n][0], k});
        }
        return t;
    }

private:
    void update_height(uint32_t n) { height_[n] = uint8_t(1 + std::max(height_[kid_[n][0]], height_[kid_[n][1]])); }

    /// Recomputes bounds and heights from n up to `top`, inclusive.
    void refit(uint32_t n, uint32_t top) {
        for (;; n = parent_[n]) {
            box_[n] = merge(box_[kid_[n][0]], box_[kid_[n][1]]);
            update_height(n);
            if (n == top) return;
        }
    }

    /// Best-first branch and bound over the subtree under `top` (not `top` itself).
    uint32_t best_sibling(uint32_t n, uint32_t top, uint32_t top_depth, uint32_t max_depth, Heap& heap) const {
        heap.clear();
        const AABB& nb = box_[n];
        const float an = nb.half_area();
        float best = INFINITY;
        uint32_t best_x = kNone;
        for (uint32_t k : kid_[top]) heap.push_back({0.0f, k, top_depth + 1});
        std::make_heap(heap.begin(), heap.end());
        while (!heap.empty()) {
            std::pop_heap(heap.begin(), heap.end());
            const Entry e = heap.back();
            heap.pop_back();
            if (e.induced + an >= best) break;  // every entry left is at least as costly
            const float grown = merge(box_[e.node], nb).half_area();
            const float c = e.induced + grown;
            if (c < best && e.depth + 1 + std::max(height_[e.node], height_[n]) <= max_depth) {
                best = c;
                best_x = e.node;
            }
            if (leaf(e.node)) continue;
            const float child_induced = e.induced + grown - area(e.node);
            if (child_induced + an >= best) continue;
            for (uint32_t k : kid_[e.node]) {
                heap.push_back({child_induced, k, e.depth + 1});
                std::push_heap(heap.begin(), heap.end());
            }
        }
        return best_x;
    }

    std::vector<AABB> box_;
    std::vector<uint32_t> parent_;
    std::vector<std::array<uint32_t, 2>> kid_;
    std::vector<uint8_t> height_;
    uint32_t root_ = 0;
};

}  // namespace

ReinsertionOptimizer::Stats ReinsertionOptimizer::optimize(BuildTree& tree) const {
    BVHLAB_CHECK(config_.max_passes >= 0, "reinsertion passes must be non-negative");
    BVHLAB_CHECK(config_.subtree_nodes >= 16, "reinsertion subtrees must have at least 16 nodes");
    Stats st;
    if (tree.nodes.size() < 7) return st;  // nothing can move
    MutableTree t(tree);
    const double root_area = std::max(1e-30, double(tree.nodes[0].bounds.half_area()));
    double area = t.interior_area();
    st.interior_area_before = st.interior_area_after = area / root_area;
    std::vector<uint32_t> pre, depth, size;
    // Subtrees of at most `cut` nodes are optimised on their own, in parallel; the few nodes
    // above them then move anywhere in the tree. The cut depends only on the tree's size, so
    // the result does not depend on the thread count.
    const auto cut = uint32_t(std::max<size_t>(config_.subtree_nodes, t.size() / 64));
    auto by_area = [&t](uint32_t a, uint32_t b) {  // the largest first, ties by slot
        const float x = t.area(a), y = t.area(b);
        return x > y || (x == y && a < b);
    };
    tbb::enumerable_thread_specific<MutableTree::Heap> heaps;
    std::atomic<uint64_t> moves{0};
    while (st.passes < config_.max_passes) {
        ++st.passes;
        t.index(pre, depth, size);
        std::vector<uint32_t> roots, top;
        for (uint32_t n : pre) {
            if (size[n] > cut)
                top.push_back(n);
            else if (n == t.root() || size[t.parent(n)] > cut)
                roots.push_back(n);
        }
        std::vector<uint32_t> first(t.size());  // preorder position
        for (size_t i = 0; i < pre.size(); ++i) first[pre[i]] = uint32_t(i);
        tbb::parallel_for(size_t(0), roots.size(), [&](size_t i) {
            const uint32_t r = roots[i];
            if (size[r] < 7) return;
            // Every node of the subtree below r, the largest first; r's children stay (a move
            // could make them children of r again, so that is checked as they come).
            std::vector<uint32_t> cand(pre.begin() + first[r] + 1, pre.begin() + first[r] + size[r]);
            std::sort(cand.begin(), cand.end(), by_area);
            MutableTree::Heap& heap = heaps.local();
            uint64_t m = 0;
            for (uint32_t n : cand)
                if (t.parent(n) != r) m += t.reinsert(n, r, depth[r], config_.max_depth, heap);
            moves += m;
        });
        t.refresh_heights(pre, size, cut);
        // The nodes above the cut, anywhere in the tree.
        std::sort(top.begin(), top.end(), by_area);
        for (uint32_t n : top) {
            const uint32_t p = t.parent(n);
            if (p == kNone || t.parent(p) == kNone) continue;
            moves += t.reinsert(n, t.root(), 0, config_.max_depth, heaps.local());
        }
        const double now = t.interior_area();
        const double gain = (area - now) / area;
        area = now;
        if (gain < config_.min_pass_gain) break;
    }
    st.moves = moves;
    st.interior_area_after = area / root_area;
    tree = t.flatten(tree);
    return st;
}

ReinsertionOptimizer::Stats optimize_by_reinsertion(BuildTree& tree, const BuildConfig& build, int passes) {
    if (passes == 0) return {};  // optimize() rejects negative counts
    ReinsertionOptimizer::Config rc;
    rc.max_passes = passes;
    rc.max_depth = build.max_depth - 1;  // builders keep leaves above max_depth
    return ReinsertionOptimizer(rc).optimize(tree);
}

}  // namespace bvhlab::accel
