// SPDX-License-Identifier: MIT
// SBVH: at each node, the best binned object split; where its children overlap by more than
// alpha x root area, also the best spatial split (chopped, clipped bins), taken only if it is
// cheaper by the spatial margin and the node's share of the budget pays for its duplicates.
// Spatial splits duplicate straddling references unless moving one whole to a side is cheaper
// ("reference unsplitting"), within a reference budget shared out down the tree.
#include "accel/builders/sbvh.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <memory>

#include "accel/builders/reinsertion.h"
#include "accel/builders/top_down.h"
#include "accel/core/check.h"
#include "accel/core/prim_ref.h"
#include "accel/core/progress.h"
#include "accel/core/sah.h"
#include "accel/core/spatial_split.h"

namespace bvhlab::accel {
namespace {

/// Pointer tree built by the parallel recursion, flattened at the end.
struct TNode {
    AABB bounds;
    std::unique_ptr<TNode> child[2];
    std::vector<uint32_t> prims;  // leaves only
};

struct Candidate {
    float weight = std::numeric_limits<float>::infinity();  // A_L N_L + A_R N_R
    int axis = -1;
    int bin = -1;
    AABB left = AABB::empty(), right = AABB::empty();
    uint32_t nl = 0, nr = 0;
    float plane = 0.0f;  // spatial splits: the plane's position on `axis`
};

AABB bounds_of(const std::vector<PrimRef>& refs) {
    AABB b = AABB::empty();
    for (const PrimRef& r : refs) b.extend(r.bounds);
    return b;
}

class Recursion {
public:
    Recursion(const SbvhBuilder::Config& c, const scene::TriangleMesh& mesh, float root_half_area)
        : c_(c), mesh_(mesh), root_area_(root_half_area) {}

    /// `budget`: how many more references this subtree may create; on return, what it left
    /// unused. A node shares what it does not use between its children in proportion to their
    /// SAH weight (area x references). Below the task threshold, one thread builds left then
    /// right, and the left subtree's leftover goes on to the right. So the tree never depends
    /// on which thread reaches the budget first.
    std::unique_ptr<TNode> build(std::vector<PrimRef> refs, const AABB& bounds, uint32_t depth, int64_t& budget) {
        auto node = std::make_unique<TNode>();
        node->bounds = bounds;
        const auto n = uint32_t(refs.size());
        AABB cb = AABB::empty();
        for (const PrimRef& r : refs) cb.extend(r.centroid());

        Candidate obj, spa;
        if (n > c_.min_leaf_size) {
            obj = object_split(refs, cb);
            // Without an object split both "children" would be the whole node.
            const float overlap_area = obj.axis < 0 ? bounds.half_area() : intersect(obj.left, obj.right).half_area();
            if (overlap_area > c_.alpha * root_area_ && budget > 0) {
                spa = spatial_split(refs, bounds);
                // A split the budget cannot pay for would be carried out without its
                // duplicates, as a worse split than its cost says: leave it out.
                if (int64_t(spa.nl) + int64_t(spa.nr) - int64_t(n) > budget) spa = Candidate{};
            }
        }
        const bool spatial = spa.weight < (1.0f - c_.spatial_margin) * obj.weight;
        const float best = spatial ? spa.weight : obj.weight;
        const float pa = bounds.half_area();
        const float cost =
            std::isfinite(best) ? c_.traversal_cost + c_.intersection_cost * (pa > 0 ? best / pa : 0.0f) : INFINITY;
        const SplitDecision d = decide_split(c_, n, depth, cost);
        if (d == SplitDecision::kLeaf) {
            node->prims.reserve(n);
            for (const PrimRef& r : refs) node->prims.push_back(r.prim_id);
            if (c_.progress) c_.progress->add(n);
            return node;
        }
        std::vector<PrimRef> left, right;
        if (d == SplitDecision::kSplit && spatial) {
            partition_spatial(refs, spa, left, right, budget);
        } else if (d == SplitDecision::kSplit) {
            const BinMapping map(cb, c_.object_bins);
            for (PrimRef& r : refs) (map.bin(r.centroid()[obj.axis], obj.axis) <= obj.bin ? left : right).push_back(r);
        }
        if (left.empty() || right.empty()) median(refs, cb, left, right);
        refs = {};  // release before recursing
        const AABB lb = bounds_of(left), rb = bounds_of(right);
        const double wl = double(lb.half_area()) * double(left.size()),
                     wr = double(rb.half_area()) * double(right.size());
        const auto budget_left = int64_t(double(budget) * (wl + wr > 0 ? wl / (wl + wr) : 0.5));
        int64_t bl = budget_left, br = budget - budget_left;
        auto l = [&] { node->child[0] = build(std::move(left), lb, depth + 1, bl); };
        auto r = [&] { node->child[1] = build(std::move(right), rb, depth + 1, br); };
        if (n >= c_.task_threshold) {
            tbb::parallel_invoke(l, r);
        } else {
            // One thread, a fixed order: what the left subtree leaves goes on to the right.
            l();
            br += bl;
            bl = 0;
            r();
        }
        budget = bl + br;  // unused, handed back up
        return node;
    }

private:
    Candidate object_split(const std::vector<PrimRef>& refs, const AABB& cb) const {
        const int nb = c_.object_bins;
        const BinMapping map(cb, nb);
        std::vector<Bin> bins(3 * size_t(nb), Bin::empty());
        bin_centroids(refs.data(), refs.size(), map, bins.data());
        const AxisSplit s = best_bin_split(bins.data(), map);
        Candidate best;
        best.weight = s.weight;
        best.axis = s.axis;
        best.bin = s.bin;
        if (best.axis >= 0) collect(&bins[size_t(best.axis) * nb], nb, best, nullptr, nullptr);
        return best;
    }

    /// Left/right bounds and counts of a chosen bin split.
    static void collect(const Bin* bins, int nb, Candidate& c, const uint32_t* entry, const uint32_t* exit) {
        for (int i = 0; i < nb; ++i) {
            if (i <= c.bin) {
                c.left.extend(bins[i].bounds);
                c.nl += entry ? entry[i] : bins[i].count;
            } else {
                c.right.extend(bins[i].bounds);
                c.nr += exit ? exit[i] : bins[i].count;
            }
        }
    }

    Candidate spatial_split(const std::vector<PrimRef>& refs, const AABB& bounds) const {
        Candidate best;
        const int nb = c_.spatial_bins;
        for (int a = 0; a < 3; ++a) {
            if (!(bounds.hi[a] > bounds.lo[a])) continue;
            auto sb = std::make_unique<SpatialBins>(a, nb, bounds);
            if (refs.size() >= 65536) {
                // Big nodes bin in parallel: one bin set per chunk, merged pairwise.
                auto merged = tbb::parallel_reduce(
                    tbb::blocked_range<size_t>(0, refs.size(), 16384), std::shared_ptr<SpatialBins>(),
                    [&](const tbb::blocked_range<size_t>& rg, std::shared_ptr<SpatialBins> acc) {
                        if (!acc) acc = std::make_shared<SpatialBins>(a, nb, bounds);
                        for (size_t i = rg.begin(); i < rg.end(); ++i) acc->add(mesh_, refs[i]);
                        return acc;
                    },
                    [nb](std::shared_ptr<SpatialBins> x, std::shared_ptr<SpatialBins> y) {
                        if (!x) return y;
                        if (!y) return x;
                        for (int i = 0; i < nb; ++i) {
                            x->bins[i].bounds.extend(y->bins[i].bounds);
                            x->entry[i] += y->entry[i];
                            x->exit[i] += y->exit[i];
                        }
                        return x;
                    });
                if (merged) *sb = *merged;
            } else {
                for (const PrimRef& r : refs) sb->add(mesh_, r);
            }
            const BinSweep sw = sweep_bins(sb->bins, nb, sb->entry, sb->exit);
            if (sw.weight < best.weight) {
                best = Candidate{};
                best.weight = sw.weight;
                best.axis = a;
                best.bin = sw.bin;
                collect(sb->bins, nb, best, sb->entry, sb->exit);
                best.plane = sb->plane(sw.bin);
            }
        }
        return best;
    }

    /// Splits at the spatial plane; straddling references are duplicated with clipped
    /// bounds, or moved whole to one side when that is cheaper (Stich et al., section 4.5).
    void partition_spatial(const std::vector<PrimRef>& refs, Candidate s, std::vector<PrimRef>& left,
                           std::vector<PrimRef>& right, int64_t& budget) const {
        const int a = s.axis;
        const float p = s.plane;
        for (const PrimRef& r : refs) {
            if (r.bounds.hi[a] <= p) {
                left.push_back(r);
                continue;
            }
            if (r.bounds.lo[a] >= p) {
                right.push_back(r);
                continue;
            }
            const float al = s.left.half_area(), ar = s.right.half_area();
            const float c_dup = al * float(s.nl) + ar * float(s.nr);
            const float c_left = merge(s.left, r.bounds).half_area() * float(s.nl) + ar * float(s.nr - 1);
            const float c_right = al * float(s.nl - 1) + merge(s.right, r.bounds).half_area() * float(s.nr);
            const bool to_left = c_left <= c_right;
            if (std::min(c_left, c_right) < c_dup || budget <= 0) {
                if (to_left) {
                    left.push_back(r);
                    s.left.extend(r.bounds);
                    --s.nr;
                } else {
                    right.push_back(r);
                    s.right.extend(r.bounds);
                    --s.nl;
                }
                continue;
            }
            PrimRef lr{AABB::empty(), r.prim_id}, rr{AABB::empty(), r.prim_id};
            split_reference(mesh_, r, a, p, lr.bounds, rr.bounds);
            // Rounding can leave one side with nothing; then the reference is not duplicated.
            if (!lr.bounds.is_empty()) left.push_back(lr);
            if (!rr.bounds.is_empty()) right.push_back(rr);
            if (!lr.bounds.is_empty() && !rr.bounds.is_empty()) --budget;
            if (lr.bounds.is_empty() && rr.bounds.is_empty()) (to_left ? left : right).push_back(r);
        }
    }

    /// Object median on the widest centroid axis, ties by id: always separates the refs.
    static void median(std::vector<PrimRef>& refs, const AABB& cb, std::vector<PrimRef>& left,
                       std::vector<PrimRef>& right) {
        const int axis = cb.largest_axis();
        std::sort(refs.begin(), refs.end(), [axis](const PrimRef& x, const PrimRef& y) {
            const float cx = x.centroid()[axis], cy = y.centroid()[axis];
            return cx < cy || (cx == cy && x.prim_id < y.prim_id);
        });
        const size_t m = refs.size() / 2;
        left.assign(refs.begin(), refs.begin() + m);
        right.assign(refs.begin() + m, refs.end());
    }

    const SbvhBuilder::Config& c_;
    const scene::TriangleMesh& mesh_;
    const float root_area_;
};

/// Depth-first flattening: siblings adjacent, a subtree's references contiguous.
BuildTree flatten(const TNode& root) {
    BuildTree t;
    t.nodes.push_back({});
    std::vector<std::pair<const TNode*, uint32_t>> stack{{&root, 0}};
    while (!stack.empty()) {
        auto [n, d] = stack.back();
        stack.pop_back();
        if (!n->child[0]) {
            t.nodes[d] = {n->bounds, uint32_t(t.prim_indices.size()), uint32_t(n->prims.size())};
            t.prim_indices.insert(t.prim_indices.end(), n->prims.begin(), n->prims.end());
            continue;
        }
        const auto k = uint32_t(t.nodes.size());
        t.nodes.resize(k + 2);
        t.nodes[d] = {n->bounds, k, 0};
        stack.push_back({n->child[1].get(), k + 1});
        stack.push_back({n->child[0].get(), k});
    }
    return t;
}

}  // namespace

BuildTree SbvhBuilder::build(const scene::TriangleMesh& mesh) const {
    BVHLAB_CHECK(mesh.triangle_count() > 0, "cannot build a BVH over zero triangles");
    BVHLAB_CHECK(config_.object_bins >= 2 && config_.object_bins <= kMaxBins && config_.spatial_bins >= 2 &&
                     config_.spatial_bins <= kMaxBins,
                 "SBVH bin counts must be in [2, 256]");
    BVHLAB_CHECK(config_.reference_budget >= 1.0f, "the SBVH reference budget must be at least 1");
    BVHLAB_CHECK(config_.alpha >= 0.0f, "SBVH alpha must be non-negative");
    BVHLAB_CHECK(config_.spatial_margin >= 0.0f && config_.spatial_margin < 1.0f,
                 "SBVH spatial margin must be in [0, 1)");
    std::vector<PrimRef> refs = make_prim_refs(mesh);
    const AABB bounds = bounds_of(refs);
    Recursion rec(config_, mesh, bounds.half_area());
    const auto budget = int64_t(double(config_.reference_budget - 1.0f) * double(mesh.triangle_count()));
    int64_t budget_left = budget;
    std::unique_ptr<TNode> root = rec.build(std::move(refs), bounds, 0, budget_left);
    BuildTree t = flatten(*root);
    destroy_iteratively(std::move(root));
    optimize_by_reinsertion(t, config_, config_.reinsertion_passes);
    return t;
}

}  // namespace bvhlab::accel
