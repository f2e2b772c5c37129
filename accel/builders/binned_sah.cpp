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
#include <memory>

#include "accel/builders/top_down.h"
#include "accel/core/binning.h"
#include "accel/core/check.h"
#include "accel/core/progress.h"
#include "accel/core/sah.h"

namespace bvhlab::accel {
namespace {

/// Bins of all three axes for one node, axis-major. Fixed capacity, so finding a split
/// allocates nothing (a heap vector per node cost ~3% of a 1M-triangle build).
struct BinSet {
    int n;
    WideBin bins[3 * kMaxBins];
    explicit BinSet(int num_bins) : n(num_bins) {
        for (int i = 0; i < 3 * n; ++i) bins[i] = WideBin::empty();
    }
    void merge(const BinSet& o) {
        for (int i = 0; i < 3 * n; ++i) {
            bins[i].lo = f4_min(bins[i].lo, o.bins[i].lo);
            bins[i].hi = f4_max(bins[i].hi, o.bins[i].hi);
            bins[i].count += o.bins[i].count;
        }
    }
};

/// Best split found by the SAH sweep over the bins.
struct Split {
    float cost = std::numeric_limits<float>::infinity();
    int axis = -1;
    int bin = -1;      // references in bins <= bin go left
    AABB left_bounds;  // the children's bounds: unions of the chosen axis's bins, exact
    AABB right_bounds;
};

/// The recursion moves references between two buffers: a node's partition reads its range
/// from one and writes both sides into the same range of the other, so its children live in
/// the other buffer. Leaves write their triangle ids into the output directly.
class Recursion {
public:
    Recursion(const BinnedSahBuilder::Config& c, std::vector<PrimRef>& refs, SparseTree& tree,
              std::vector<uint32_t>& ids)
        : c_(c), buf_{refs.data(), nullptr}, tree_(tree), ids_(ids) {
        scratch_.reset(new PrimRef[refs.size()]);  // uninitialised: written before it is read
        buf_[1] = scratch_.get();
    }

    /// Builds the subtree over buffer `in`'s [b, e), whose bounds and centroid bounds are given.
    void build(uint32_t slot, uint32_t b, uint32_t e, const AABB& bounds, const AABB& cbounds, uint32_t depth,
               int in = 0) {
        const uint32_t count = e - b;
        PrimRef* refs = buf_[in];
        if (count <= c_.sweep_threshold) {
            build_small(refs, slot, b, e, bounds, cbounds, depth);
            return;
        }
        BinMapping map(cbounds, c_.num_bins);
        Split split;
        if (count > c_.min_leaf_size) split = find_split(refs, b, e, bounds, map);
        SplitDecision d = decide_split(c_, count, depth, split.cost);
        if (d == SplitDecision::kLeaf) {
            set_leaf(refs, slot, b, e, bounds);
            return;
        }
        AABB lb, lc, rb, rc;
        uint32_t m;
        int child_in = in;
        if (d == SplitDecision::kSplit) {
            m = partition(refs, buf_[1 - in], b, e, split, map, lc, rc);
            lb = split.left_bounds;
            rb = split.right_bounds;
            child_in = 1 - in;
        } else {
            m = median(refs, b, e, cbounds);
            range_bounds(refs, b, m, lb, lc);
            range_bounds(refs, m, e, rb, rc);
        }
        tree_.set_interior(slot, b, m, bounds);
        auto left = [&] { build(SparseTree::left_slot(slot), b, m, lb, lc, depth + 1, child_in); };
        auto right = [&] { build(SparseTree::right_slot(slot, b, m), m, e, rb, rc, depth + 1, child_in); };
        if (count >= c_.task_threshold) {
            tbb::parallel_invoke(left, right);
        } else {
            left();
            right();
        }
    }

    /// Bounds and centroid bounds of the first buffer's [b, e) (the root, before any split).
    void root_bounds(uint32_t b, uint32_t e, AABB& bounds, AABB& cbounds) const {
        range_bounds(buf_[0], b, e, bounds, cbounds);
    }

private:
    void set_leaf(const PrimRef* refs, uint32_t slot, uint32_t b, uint32_t e, const AABB& bounds) {
        tree_.set_leaf(slot, b, e, bounds);
        for (uint32_t i = b; i < e; ++i) ids_[i] = refs[i].prim_id;
        if (c_.progress) c_.progress->add(e - b);
    }

    /// Exact SAH sweep for a small node: sort by centroid on each axis, sweep, recurse. Each
    /// axis sorts 12-byte keys (centroid, id, position), not the 28-byte references; the
    /// references are permuted once, into the order of the axis chosen (or of the last axis
    /// sorted, as a sort of the references themselves left them). Stays in its buffer.
    void build_small(PrimRef* refs, uint32_t slot, uint32_t b, uint32_t e, const AABB& bounds, const AABB& cbounds,
                     uint32_t depth) {
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
                for (uint32_t i = 0; i < count; ++i) k[i] = {refs[b + i].centroid()[a], refs[b + i].prim_id, i};
                std::sort(k, k + count, [](const Key& x, const Key& y) {
                    return x.c < y.c || (x.c == y.c && x.prim_id < y.prim_id);
                });
                AABB acc = AABB::empty();
                for (uint32_t i = count - 1; i > 0; --i) {
                    acc.extend(refs[b + k[i].pos].bounds);
                    right_area[i] = acc.half_area();
                }
                acc = AABB::empty();
                for (uint32_t i = 1; i < count; ++i) {
                    acc.extend(refs[b + k[i - 1].pos].bounds);
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
            for (uint32_t i = 0; i < count; ++i) tmp[i] = refs[b + keys[a][i].pos];
            std::copy(tmp, tmp + count, refs + b);
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
            set_leaf(refs, slot, b, e, bounds);
            return;
        }
        uint32_t m;
        if (d == SplitDecision::kSplit) {
            m = b + best_pos;
        } else {
            m = median(refs, b, e, cbounds);
        }
        tree_.set_interior(slot, b, m, bounds);
        AABB lb, lc, rb, rc;
        range_bounds(refs, b, m, lb, lc);
        range_bounds(refs, m, e, rb, rc);
        build_small(refs, SparseTree::left_slot(slot), b, m, lb, lc, depth + 1);
        build_small(refs, SparseTree::right_slot(slot, b, m), m, e, rb, rc, depth + 1);
    }

    /// Bounds and centroid bounds of refs[b, e).
    void range_bounds(const PrimRef* refs, uint32_t b, uint32_t e, AABB& bounds, AABB& cbounds) const {
        using Pair = std::pair<AABB, AABB>;
        auto span = [refs](uint32_t lo, uint32_t hi, Pair acc) {
            for (uint32_t i = lo; i < hi; ++i) {
                acc.first.extend(refs[i].bounds);
                acc.second.extend(refs[i].centroid());
            }
            return acc;
        };
        Pair r{AABB::empty(), AABB::empty()};
        if (e - b >= c_.parallel_bin_threshold) {
            r = tbb::parallel_reduce(
                tbb::blocked_range<uint32_t>(b, e, 8192), r,
                [&](const auto& rg, Pair acc) { return span(rg.begin(), rg.end(), acc); },
                [](Pair x, const Pair& y) {
                    x.first.extend(y.first);
                    x.second.extend(y.second);
                    return x;
                });
        } else {
            r = span(b, e, r);
        }
        bounds = r.first;
        cbounds = r.second;
    }

    Split find_split(const PrimRef* refs, uint32_t b, uint32_t e, const AABB& bounds, const BinMapping& map) const {
        const int nb = c_.num_bins;
        BinSet set(nb);
        if (e - b >= c_.parallel_bin_threshold) {
            set = tbb::parallel_reduce(
                tbb::blocked_range<uint32_t>(b, e, 16384), BinSet(nb),
                [&](const auto& rg, BinSet acc) {
                    bin_centroids(refs + rg.begin(), rg.end() - rg.begin(), map, acc.bins);
                    return acc;
                },
                [](BinSet x, const BinSet& y) {
                    x.merge(y);
                    return x;
                });
        } else {
            bin_centroids(refs + b, e - b, map, set.bins);
        }
        Bin bins[3 * kMaxBins];
        for (int i = 0; i < 3 * nb; ++i) bins[i] = set.bins[i].to_bin();
        const AxisSplit s = best_bin_split(bins, map);
        Split best;
        if (s.axis < 0) return best;
        const float parent_area = bounds.half_area();
        best.cost = c_.traversal_cost + c_.intersection_cost * (parent_area > 0.0f ? s.weight / parent_area : 0.0f);
        best.axis = s.axis;
        best.bin = s.bin;
        best.left_bounds = best.right_bounds = AABB::empty();
        for (int i = 0; i < nb; ++i)
            (i <= s.bin ? best.left_bounds : best.right_bounds).extend(bins[s.axis * nb + i].bounds);
        return best;
    }

    /// Stable-left partition of in[b, e) into out[b, e) by bin, without branches: each
    /// reference is stored at both ends and the side it belongs to advances (the other store is
    /// overwritten later), and the two sides' centroid bounds are kept by select. Left keeps
    /// its order, the right side is reversed; neither changes the tree, as every later choice
    /// breaks ties by triangle id. Replaced an in-place Hoare partition whose branches followed
    /// the data: 32% of a 1M-soup build (NOTES.md, session 15).
    uint32_t partition(const PrimRef* in, PrimRef* out, uint32_t b, uint32_t e, const Split& s, const BinMapping& map,
                       AABB& lc, AABB& rc) const {
        const int axis = s.axis;
        const float origin = map.origin[axis], scale = map.scale[axis];
        const int last = map.num_bins - 1;
        const F4 inf = {FLT_MAX, FLT_MAX, FLT_MAX, 0.0f};
        F4 llo = inf, lhi = -inf, rlo = inf, rhi = -inf;
        int64_t l = b, r = int64_t(e) - 1;
        for (uint32_t i = b; i < e; ++i) {
            const PrimRef& ref = in[i];
            F4 lo, hi;
            load_corners(ref, lo, hi);
            const F4 c = (lo + hi) * 0.5f;
            int bin = int((c[axis] - origin) * scale);
            bin = std::min(std::max(bin, 0), last);
            const bool go_left = bin <= s.bin;
            out[l] = ref;
            out[r] = ref;
            l += go_left;
            r -= !go_left;
            const I4 m = go_left ? I4{-1, -1, -1, -1} : I4{0, 0, 0, 0};
            llo = f4_min(llo, m ? c : llo);
            lhi = f4_max(lhi, m ? c : lhi);
            rlo = f4_min(rlo, m ? rlo : c);
            rhi = f4_max(rhi, m ? rhi : c);
        }
        lc = {vec3(llo), vec3(lhi)};
        rc = {vec3(rlo), vec3(rhi)};
        return uint32_t(l);
    }

    /// Object-median split on the widest centroid axis; ties broken by id so the result is
    /// deterministic even when every centroid coincides.
    uint32_t median(PrimRef* refs, uint32_t b, uint32_t e, const AABB& cbounds) const {
        const int axis = cbounds.largest_axis();
        const uint32_t m = b + (e - b) / 2;
        std::nth_element(refs + b, refs + m, refs + e, [axis](const PrimRef& x, const PrimRef& y) {
            float cx = x.centroid()[axis], cy = y.centroid()[axis];
            return cx < cy || (cx == cy && x.prim_id < y.prim_id);
        });
        return m;
    }

    const BinnedSahBuilder::Config& c_;
    PrimRef* buf_[2];
    std::unique_ptr<PrimRef[]> scratch_;
    SparseTree& tree_;
    std::vector<uint32_t>& ids_;
};

}  // namespace

BuildTree BinnedSahBuilder::build(const scene::TriangleMesh& mesh) const { return build(make_prim_refs(mesh)); }

BuildTree BinnedSahBuilder::build(std::vector<PrimRef> refs) const {
    BVHLAB_CHECK(!refs.empty(), "cannot build a BVH over zero triangles");
    BVHLAB_CHECK(config_.num_bins >= 2 && config_.num_bins <= kMaxBins, "num_bins must be in [2, 256]");
    BVHLAB_CHECK(config_.sweep_threshold <= 64, "sweep_threshold must be at most 64");
    BVHLAB_CHECK(refs.size() < (size_t(1) << 31), "too many references for 32-bit indices");
    SparseTree sparse(refs.size());
    std::vector<uint32_t> ids(refs.size());
    Recursion rec(config_, refs, sparse, ids);
    AABB bounds, cbounds;
    rec.root_bounds(0, uint32_t(refs.size()), bounds, cbounds);
    rec.build(0, 0, uint32_t(refs.size()), bounds, cbounds, 0);
    return sparse.compact(std::move(ids));
}

}  // namespace bvhlab::accel
