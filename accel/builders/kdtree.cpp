// SPDX-License-Identifier: MIT
// O(N log N) SAH kd-tree build (Wald & Havran 2006). Each node keeps its events sorted by
// (position, axis, type); one sweep finds the best plane on all three axes; triangles are
// then classified left / right / both, only the straddling ones are clipped to each child's
// voxel ("perfect splits"), and their few new events are sorted and merged into the already
// sorted lists of the others. Node events refer to node-local triangle slots, so concurrent
// subtrees never share state.
#include "accel/builders/kdtree.h"

#include <tbb/parallel_invoke.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <memory>

#include "accel/builders/top_down.h"
#include "accel/core/check.h"
#include "accel/core/clip.h"

namespace bvhlab::accel {
namespace {

enum : uint8_t { kEnd = 0, kPlanar = 1, kStart = 2 };

struct Event {
    float pos;
    uint32_t slot;  // node-local triangle slot
    uint8_t axis;
    uint8_t type;
};

/// Event order: position, axis, type (end < planar < start), slot. A functor, so sort and
/// merge inline it (as a function pointer it cost ~10% of the build).
struct EventLess {
    bool operator()(const Event& a, const Event& b) const {
        if (a.pos != b.pos) return a.pos < b.pos;
        if (a.axis != b.axis) return a.axis < b.axis;
        if (a.type != b.type) return a.type < b.type;
        return a.slot < b.slot;
    }
};
constexpr EventLess event_less{};

void add_events(std::vector<Event>& out, const AABB& b, uint32_t slot) {
    for (uint8_t k = 0; k < 3; ++k) {
        if (b.lo[k] == b.hi[k]) {
            out.push_back({b.lo[k], slot, k, kPlanar});
        } else {
            out.push_back({b.lo[k], slot, k, kStart});
            out.push_back({b.hi[k], slot, k, kEnd});
        }
    }
}

struct KNode {
    uint32_t axis = 3;
    float split = 0.0f;
    std::unique_ptr<KNode> child[2];
    std::vector<uint32_t> prims;
};

/// A node's work: its voxel, its triangles (global ids) and their sorted events.
struct Work {
    AABB voxel;
    std::vector<uint32_t> tris;
    std::vector<Event> events;
};

struct Plane {
    float cost = INFINITY;
    int axis = -1;
    float pos = 0.0f;
    bool planar_left = true;
};

class Recursion {
public:
    Recursion(const KdTreeBuilder::Config& c, const TriangleMesh& mesh, int max_depth)
        : c_(c), mesh_(mesh), max_depth_(max_depth) {}

    std::unique_ptr<KNode> build(Work w, int depth) {
        auto node = std::make_unique<KNode>();
        const auto n = uint32_t(w.tris.size());
        const Plane p = depth < max_depth_ ? find_plane(w) : Plane{};
        if (!(p.cost < c_.intersection_cost * float(n))) {
            node->prims = std::move(w.tris);
            return node;
        }
        Work left, right;
        split(w, p, left, right);
        w = Work{};
        node->axis = uint32_t(p.axis);
        node->split = p.pos;
        auto l = [&] { node->child[0] = build(std::move(left), depth + 1); };
        auto r = [&] { node->child[1] = build(std::move(right), depth + 1); };
        if (n >= c_.task_threshold) tbb::parallel_invoke(l, r); else { l(); r(); }
        return node;
    }

private:
    float sah(const AABB& v, int k, float pos, uint32_t nl, uint32_t nr, float inv_area) const {
        AABB vl = v, vr = v;
        vl.hi[k] = pos;
        vr.lo[k] = pos;
        const float cost = c_.traversal_cost +
                           c_.intersection_cost * (vl.area() * inv_area * float(nl) + vr.area() * inv_area * float(nr));
        return (nl == 0 || nr == 0) ? cost * (1.0f - c_.empty_bonus) : cost;
    }

    /// One sweep over the sorted events finds the cheapest plane on all axes.
    Plane find_plane(const Work& w) const {
        Plane best;
        const float area = w.voxel.area();
        if (!(area > 0.0f) || w.tris.empty()) return best;
        const float inv_area = 1.0f / area;
        const auto n = uint32_t(w.tris.size());
        uint32_t nl[3] = {0, 0, 0}, nr[3] = {n, n, n};
        const std::vector<Event>& e = w.events;
        for (size_t i = 0; i < e.size();) {
            const float pos = e[i].pos;
            const int k = e[i].axis;
            uint32_t ends = 0, planars = 0, starts = 0;
            while (i < e.size() && e[i].axis == k && e[i].pos == pos && e[i].type == kEnd) ++ends, ++i;
            while (i < e.size() && e[i].axis == k && e[i].pos == pos && e[i].type == kPlanar) ++planars, ++i;
            while (i < e.size() && e[i].axis == k && e[i].pos == pos && e[i].type == kStart) ++starts, ++i;
            nr[k] -= planars + ends;
            // Planes on the voxel's boundary would leave an empty, flat child: skip them.
            if (pos > w.voxel.lo[k] && pos < w.voxel.hi[k]) {
                const float cl = sah(w.voxel, k, pos, nl[k] + planars, nr[k], inv_area);
                const float cr = sah(w.voxel, k, pos, nl[k], nr[k] + planars, inv_area);
                if (cl < best.cost) best = {cl, k, pos, true};
                if (cr < best.cost) best = {cr, k, pos, false};
            }
            nl[k] += starts + planars;
        }
        return best;
    }

    /// Per-thread temporaries of split(), reused across nodes (the children's own vectors
    /// must be fresh; these need not be).
    struct Scratch {
        std::vector<uint8_t> side;
        std::vector<uint32_t> to_left, to_right;
        std::vector<Event> nl, nr;
    };

    void split(const Work& w, const Plane& p, Work& left, Work& right) const {
        enum : uint8_t { kBoth = 0, kLeftOnly = 1, kRightOnly = 2 };
        static thread_local Scratch scratch;  // used only between here and the merges below
        const size_t n = w.tris.size();
        std::vector<uint8_t>& side = scratch.side;
        side.assign(n, kBoth);
        for (const Event& e : w.events) {
            if (e.axis != p.axis) continue;
            if (e.type == kEnd && e.pos <= p.pos) side[e.slot] = kLeftOnly;
            else if (e.type == kStart && e.pos >= p.pos) side[e.slot] = kRightOnly;
            else if (e.type == kPlanar) {
                if (e.pos < p.pos || (e.pos == p.pos && p.planar_left)) side[e.slot] = kLeftOnly;
                else side[e.slot] = kRightOnly;
            }
        }
        left.voxel = right.voxel = w.voxel;
        left.voxel.hi[p.axis] = p.pos;
        right.voxel.lo[p.axis] = p.pos;
        // Slots of the one-sided triangles in each child, in their old order.
        constexpr uint32_t kNone = ~0u;
        std::vector<uint32_t>& to_left = scratch.to_left;
        std::vector<uint32_t>& to_right = scratch.to_right;
        to_left.assign(n, kNone);
        to_right.assign(n, kNone);
        for (size_t s = 0; s < n; ++s) {
            if (side[s] == kLeftOnly) {
                to_left[s] = uint32_t(left.tris.size());
                left.tris.push_back(w.tris[s]);
            } else if (side[s] == kRightOnly) {
                to_right[s] = uint32_t(right.tris.size());
                right.tris.push_back(w.tris[s]);
            }
        }
        // Their events stay sorted: filter and renumber.
        std::vector<Event> el, er;
        el.reserve(w.events.size() / 2 + 16);
        er.reserve(w.events.size() / 2 + 16);
        for (const Event& e : w.events) {
            if (side[e.slot] == kLeftOnly) el.push_back({e.pos, to_left[e.slot], e.axis, e.type});
            else if (side[e.slot] == kRightOnly) er.push_back({e.pos, to_right[e.slot], e.axis, e.type});
        }
        // Straddling triangles: clip to each child's voxel, new events, sort, merge.
        std::vector<Event>& nl = scratch.nl;
        std::vector<Event>& nr = scratch.nr;
        nl.clear();
        nr.clear();
        for (size_t s = 0; s < n; ++s) {
            if (side[s] != kBoth) continue;
            const uint32_t t = w.tris[s];
            const Vec3 a = mesh_.vertex(t, 0), b = mesh_.vertex(t, 1), c = mesh_.vertex(t, 2);
            const AABB bl = clip_triangle(a, b, c, left.voxel).bounds;
            const AABB br = clip_triangle(a, b, c, right.voxel).bounds;
            if (!bl.is_empty()) {
                add_events(nl, bl, uint32_t(left.tris.size()));
                left.tris.push_back(t);
            }
            if (!br.is_empty()) {
                add_events(nr, br, uint32_t(right.tris.size()));
                right.tris.push_back(t);
            }
        }
        std::sort(nl.begin(), nl.end(), event_less);
        std::sort(nr.begin(), nr.end(), event_less);
        left.events.resize(el.size() + nl.size());
        std::merge(el.begin(), el.end(), nl.begin(), nl.end(), left.events.begin(), event_less);
        right.events.resize(er.size() + nr.size());
        std::merge(er.begin(), er.end(), nr.begin(), nr.end(), right.events.begin(), event_less);
    }

    const KdTreeBuilder::Config& c_;
    const TriangleMesh& mesh_;
    const int max_depth_;
};

KdTree flatten(const KNode& root, const AABB& bounds) {
    KdTree t;
    t.bounds = bounds;
    t.nodes.push_back({});
    std::vector<std::pair<const KNode*, uint32_t>> stack{{&root, 0}};
    while (!stack.empty()) {
        auto [n, d] = stack.back();
        stack.pop_back();
        if (n->axis == 3) {
            t.nodes[d] = {0.0f, 3, uint32_t(t.prim_indices.size()), uint32_t(n->prims.size())};
            t.prim_indices.insert(t.prim_indices.end(), n->prims.begin(), n->prims.end());
            continue;
        }
        const auto k = uint32_t(t.nodes.size());
        t.nodes.resize(k + 2);
        t.nodes[d] = {n->split, n->axis, k, 0};
        stack.push_back({n->child[1].get(), k + 1});
        stack.push_back({n->child[0].get(), k});
    }
    return t;
}

}  // namespace

int KdTreeBuilder::max_depth_for(size_t n) const {
    if (config_.max_depth >= 0) return std::min(config_.max_depth, 64);
    return std::min(64, int(8.0 + 1.3 * std::log2(double(std::max<size_t>(n, 1)))));
}

KdTree KdTreeBuilder::build(const TriangleMesh& mesh) const {
    BVHLAB_CHECK(mesh.triangle_count() > 0, "cannot build a kd-tree over zero triangles");
    BVHLAB_CHECK(config_.traversal_cost > 0 && config_.intersection_cost > 0, "kd-tree costs must be positive");
    BVHLAB_CHECK(config_.empty_bonus >= 0 && config_.empty_bonus < 1, "the empty-space bonus must be in [0, 1)");
    Work root;
    root.voxel = mesh.bounds();
    const size_t n = mesh.triangle_count();
    root.tris.resize(n);
    root.events.reserve(6 * n);
    for (uint32_t t = 0; t < n; ++t) {
        root.tris[t] = t;
        add_events(root.events, mesh.triangle_bounds(t), t);
    }
    tbb::parallel_sort(root.events.begin(), root.events.end(), event_less);
    Recursion rec(config_, mesh, max_depth_for(n));
    const AABB bounds = root.voxel;
    std::unique_ptr<KNode> tree = rec.build(std::move(root), 0);
    KdTree out = flatten(*tree, bounds);
    destroy_iteratively(std::move(tree));
    return out;
}

namespace {

/// Visits every node with its cell and depth (children after their parent).
template <typename F>
void walk_cells(const KdTree& tree, F&& visit) {
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
        l.hi[int(n.axis)] = n.split;
        r.lo[int(n.axis)] = n.split;
        stack.push_back({n.child, l, it.depth + 1});
        stack.push_back({n.child + 1, r, it.depth + 1});
    }
}

}  // namespace

KdTreeStats compute_kd_stats(const KdTree& tree, const KdTreeBuilder::Config& c) {
    KdTreeStats s;
    if (tree.nodes.empty()) return s;
    s.nodes = tree.nodes.size();
    const double root = tree.bounds.area();
    walk_cells(tree, [&](uint32_t, const KdNode& n, const AABB& cell, uint32_t depth) {
        const double rel = root > 0 ? double(cell.area()) / root : 0.0;
        if (n.is_leaf()) {
            ++s.leaves;
            s.references += n.count;
            s.depth = std::max(s.depth, depth);
            s.max_leaf_size = std::max(s.max_leaf_size, n.count);
            s.sah += rel * c.intersection_cost * n.count;
        } else {
            s.sah += rel * c.traversal_cost;
        }
        return true;
    });
    return s;
}

std::string validate_kd(const KdTree& tree, size_t triangles) {
    if (tree.nodes.empty()) return "kd-tree has no nodes";
    std::vector<uint8_t> seen(tree.nodes.size(), 0);
    std::string err;
    walk_cells(tree, [&](uint32_t i, const KdNode& n, const AABB& cell, uint32_t) {
        const std::string where = "kd node " + std::to_string(i) + ": ";
        if (seen[i]++) err = where + "reached twice";
        else if (n.axis > 3) err = where + "axis out of range";
        else if (n.is_leaf() && size_t(n.child) + n.count > tree.prim_indices.size()) err = where + "leaf range out of range";
        else if (!n.is_leaf() && size_t(n.child) + 1 >= tree.nodes.size()) err = where + "child out of range";
        else if (!n.is_leaf() && !(n.split >= cell.lo[int(n.axis)] && n.split <= cell.hi[int(n.axis)]))
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
