// SPDX-License-Identifier: MIT
// Binned SAH builder: centroid binning per node (Wald 2007), in-place partition of PrimRefs,
// TBB tasks per subtree and a parallel binning pass for large nodes.
#include "accel/builders/binned_sah.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "accel/builders/top_down.h"
#include "accel/core/binning.h"
#include "accel/core/check.h"
#include "accel/core/sah.h"

namespace bvhlab::accel {
namespace {

/// Bins of all three axes for one node, axis-major. Fixed capacity, so finding a split
/// allocates nothing (a heap vector per node cost ~3% of a 1M-triangle build).
struct BinSet {
    int n;
    Bin bins[3 * kMaxBins];
    explicit BinSet(int num_bins) : n(num_bins) {
        for (int i = 0; i < 3 * n; ++i) bins[i] = Bin::empty();
    }
    void merge(const BinSet& o) {
        for (int i = 0; i < 3 * n; ++i) {
            bins[i].bounds.extend(o.bins[i].bounds);
            bins[i].count += o.bins[i].count;
        }
    }
};

/// Best split found by the SAH sweep over the bins.
struct Split {
    float cost = std::numeric_limits<float>::infinity();
    int axis = -1;
    int bin = -1;  // references in bins <= bin go left
};

class Recursion {
public:
    Recursion(const BinnedSahBuilder::Config& c, std::vector<PrimRef>& refs, SparseTree& tree)
        : c_(c), refs_(refs), tree_(tree) {}

    /// Builds the subtree over refs_[b, e) whose bounds and centroid bounds are given.
    void build(uint32_t slot, uint32_t b, uint32_t e, const AABB& bounds, const AABB& cbounds, uint32_t depth) {
        const uint32_t count = e - b;
        if (count <= c_.sweep_threshold) {
            build_small(slot, b, e, bounds, cbounds, depth);
            return;
        }
        BinMapping map(cbounds, c_.num_bins);
        Split split;
        if (count > c_.min_leaf_size) split = find_split(b, e, bounds, map);
        SplitDecision d = decide_split(c_, count, depth, split.cost);
        if (d == SplitDecision::kLeaf) {
            tree_.set_leaf(slot, b, e, bounds);
            return;
        }
        AABB lb, lc, rb, rc;
        uint32_t m;
        if (d == SplitDecision::kSplit) {
            m = partition(b, e, split, map, lb, lc, rb, rc);
        } else {
            m = median(b, e, cbounds);
            range_bounds(b, m, lb, lc);
            range_bounds(m, e, rb, rc);
        }
        tree_.set_interior(slot, b, m, bounds);
        auto left = [&] { build(SparseTree::left_slot(slot), b, m, lb, lc, depth + 1); };
        auto right = [&] { build(SparseTree::right_slot(slot, b, m), m, e, rb, rc, depth + 1); };
        if (count >= c_.task_threshold) {
            tbb::parallel_invoke(left, right);
        } else {
            left();
            right();
        }
    }

    /// Exact SAH sweep for a small node: sort by centroid on each axis, sweep, recurse. Each
    /// axis sorts 12-byte keys (centroid, id, position), not the 28-byte references; the
    /// references are permuted once, into the order of the axis chosen (or of the last axis
    /// sorted, as a sort of the references themselves left them), so the tree is the same.
    void build_small(uint32_t slot, uint32_t b, uint32_t e, const AABB& bounds, const AABB& cbounds, uint32_t depth) {
        const uint32_t count = e - b;
        float best_weight = std::numeric_limits<float>::infinity();
        int best_axis = -1;
        uint32_t best_pos = 0;  // size of the left side
        int sorted_axis = -1;
        struct Key {
            float c;
            uint32_t prim_id, pos;
        };
        Key keys[3][64];
        if (count > c_.min_leaf_size) {
            float right_area[64];
            for (int a = 0; a < 3; ++a) {
                if (cbounds.extent()[a] <= 0.0f) continue;
                sorted_axis = a;
                Key* k = keys[a];
                for (uint32_t i = 0; i < count; ++i) k[i] = {refs_[b + i].centroid()[a], refs_[b + i].prim_id, i};
                std::sort(k, k + count, [](const Key& x, const Key& y) {
                    return x.c < y.c || (x.c == y.c && x.prim_id < y.prim_id);
                });
                AABB acc = AABB::empty();
                for (uint32_t i = count - 1; i > 0; --i) {
                    acc.extend(refs_[b + k[i].pos].bounds);
                    right_area[i] = acc.half_area();
                }
                acc = AABB::empty();
                for (uint32_t i = 1; i < count; ++i) {
                    acc.extend(refs_[b + k[i - 1].pos].bounds);
                    // No split between equal centroids: a plane could not reproduce it.
                    if (k[i - 1].c == k[i].c) continue;
                    const float w = acc.half_area() * float(i) + right_area[i] * float(count - i);
                    if (w < best_weight) {
                        best_weight = w;
                        best_axis = a;
                        best_pos = i;
                    }
                }
            }
        }
        auto permute = [&](int a) {
            PrimRef tmp[64];
            for (uint32_t i = 0; i < count; ++i) tmp[i] = refs_[b + keys[a][i].pos];
            std::copy(tmp, tmp + count, refs_.begin() + b);
        };
        float cost = std::numeric_limits<float>::infinity();
        if (best_axis >= 0) {
            const float pa = bounds.half_area();
            cost = c_.traversal_cost + c_.intersection_cost * (pa > 0.0f ? best_weight / pa : 0.0f);
        }
        const SplitDecision d = decide_split(c_, count, depth, cost);
        if (d == SplitDecision::kSplit)
            permute(best_axis);
        else if (sorted_axis >= 0)
            permute(sorted_axis);
        if (d == SplitDecision::kLeaf) {
            tree_.set_leaf(slot, b, e, bounds);
            return;
        }
        uint32_t m;
        if (d == SplitDecision::kSplit) {
            m = b + best_pos;
        } else {
            m = median(b, e, cbounds);
        }
        tree_.set_interior(slot, b, m, bounds);
        AABB lb, lc, rb, rc;
        range_bounds(b, m, lb, lc);
        range_bounds(m, e, rb, rc);
        build_small(SparseTree::left_slot(slot), b, m, lb, lc, depth + 1);
        build_small(SparseTree::right_slot(slot, b, m), m, e, rb, rc, depth + 1);
    }

    /// Bounds and centroid bounds of refs_[b, e).
    void range_bounds(uint32_t b, uint32_t e, AABB& bounds, AABB& cbounds) const {
        bounds = AABB::empty();
        cbounds = AABB::empty();
        if (e - b >= c_.parallel_bin_threshold) {
            using Pair = std::pair<AABB, AABB>;
            Pair r = tbb::parallel_reduce(
                tbb::blocked_range<uint32_t>(b, e, 8192), Pair{AABB::empty(), AABB::empty()},
                [&](const auto& rg, Pair acc) {
                    for (uint32_t i = rg.begin(); i < rg.end(); ++i) {
                        acc.first.extend(refs_[i].bounds);
                        acc.second.extend(refs_[i].centroid());
                    }
                    return acc;
                },
                [](Pair x, const Pair& y) {
                    x.first.extend(y.first);
                    x.second.extend(y.second);
                    return x;
                });
            bounds = r.first;
            cbounds = r.second;
            return;
        }
        for (uint32_t i = b; i < e; ++i) {
            bounds.extend(refs_[i].bounds);
            cbounds.extend(refs_[i].centroid());
        }
    }

private:
    void bin_range(uint32_t b, uint32_t e, const BinMapping& map, BinSet& set) const {
        bin_centroids(&refs_[b], e - b, map, set.bins);
    }

    Split find_split(uint32_t b, uint32_t e, const AABB& bounds, const BinMapping& map) const {
        const int nb = c_.num_bins;
        BinSet set(nb);
        if (e - b >= c_.parallel_bin_threshold) {
            set = tbb::parallel_reduce(
                tbb::blocked_range<uint32_t>(b, e, 16384), BinSet(nb),
                [&](const auto& rg, BinSet acc) {
                    bin_range(rg.begin(), rg.end(), map, acc);
                    return acc;
                },
                [](BinSet x, const BinSet& y) {
                    x.merge(y);
                    return x;
                });
        } else {
            bin_range(b, e, map, set);
        }
        const AxisSplit s = best_bin_split(set.bins, map);
        Split best;
        if (s.axis < 0) return best;
        const float parent_area = bounds.half_area();
        best.cost = c_.traversal_cost + c_.intersection_cost * (parent_area > 0.0f ? s.weight / parent_area : 0.0f);
        best.axis = s.axis;
        best.bin = s.bin;
        return best;
    }

    /// Hoare partition by bin that also gathers both sides' bounds and centroid bounds, so
    /// the children need no separate bounds pass.
    uint32_t partition(uint32_t b, uint32_t e, const Split& s, const BinMapping& map, AABB& lb, AABB& lc, AABB& rb,
                       AABB& rc) {
        lb = lc = rb = rc = AABB::empty();
        auto left = [&](const PrimRef& r) { return map.bin(r.centroid()[s.axis], s.axis) <= s.bin; };
        auto add = [](const PrimRef& r, AABB& box, AABB& cbox) {
            box.extend(r.bounds);
            cbox.extend(r.centroid());
        };
        uint32_t i = b, j = e;
        while (true) {
            while (i < j && left(refs_[i])) add(refs_[i++], lb, lc);
            while (i < j && !left(refs_[j - 1])) add(refs_[--j], rb, rc);
            if (i >= j) break;
            std::swap(refs_[i], refs_[j - 1]);
            add(refs_[i++], lb, lc);
            add(refs_[--j], rb, rc);
        }
        return i;
    }

    /// Object-median split on the widest centroid axis; ties broken by id so the result is
    /// deterministic even when every centroid coincides.
    uint32_t median(uint32_t b, uint32_t e, const AABB& cbounds) {
        const int axis = cbounds.largest_axis();
        const uint32_t m = b + (e - b) / 2;
        std::nth_element(refs_.begin() + b, refs_.begin() + m, refs_.begin() + e,
                         [axis](const PrimRef& x, const PrimRef& y) {
                             float cx = x.centroid()[axis], cy = y.centroid()[axis];
                             return cx < cy || (cx == cy && x.prim_id < y.prim_id);
                         });
        return m;
    }

    const BinnedSahBuilder::Config& c_;
    std::vector<PrimRef>& refs_;
    SparseTree& tree_;
};

}  // namespace

BuildTree BinnedSahBuilder::build(const TriangleMesh& mesh) const { return build(make_prim_refs(mesh)); }

BuildTree BinnedSahBuilder::build(std::vector<PrimRef> refs) const {
    BVHLAB_CHECK(!refs.empty(), "cannot build a BVH over zero triangles");
    BVHLAB_CHECK(config_.num_bins >= 2 && config_.num_bins <= kMaxBins, "num_bins must be in [2, 256]");
    BVHLAB_CHECK(config_.sweep_threshold <= 64, "sweep_threshold must be at most 64");
    BVHLAB_CHECK(refs.size() < (size_t(1) << 31), "too many references for 32-bit indices");
    SparseTree sparse(refs.size());
    Recursion rec(config_, refs, sparse);
    AABB bounds, cbounds;
    rec.range_bounds(0, uint32_t(refs.size()), bounds, cbounds);
    rec.build(0, 0, uint32_t(refs.size()), bounds, cbounds, 0);
    std::vector<uint32_t> ids(refs.size());
    for (size_t i = 0; i < refs.size(); ++i) ids[i] = refs[i].prim_id;
    return sparse.compact(std::move(ids));
}

}  // namespace bvhlab::accel
