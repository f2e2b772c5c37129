// SPDX-License-Identifier: MIT
// Full-sweep SAH: presorted centroid orders per axis, a right-to-left area sweep and a
// left-to-right cost sweep per node, then stable partitions that keep every order sorted.
#include "accel/builders/sweep_sah.h"

#include <tbb/parallel_invoke.h>
#include <tbb/parallel_sort.h>

#include <cmath>
#include <limits>

#include "accel/builders/top_down.h"
#include "accel/core/check.h"
#include "accel/core/prim_ref.h"
#include "accel/core/progress.h"
#include "accel/core/sah.h"

namespace bvhlab::accel {
namespace {

class Recursion {
public:
    Recursion(const SweepSahBuilder::Config& c, const std::vector<PrimRef>& refs, SparseTree& tree)
        : c_(c), refs_(refs), tree_(tree), goes_left_(refs.size()), area_(refs.size()), scratch_(refs.size()) {
        for (int a = 0; a < 3; ++a) {
            order_[a].resize(refs.size());
            for (uint32_t i = 0; i < refs.size(); ++i) order_[a][i] = i;
            // Ties are broken by id, so all three orders and the result are deterministic.
            tbb::parallel_sort(order_[a].begin(), order_[a].end(), [&](uint32_t x, uint32_t y) {
                float cx = refs_[x].centroid()[a], cy = refs_[y].centroid()[a];
                return cx < cy || (cx == cy && x < y);
            });
        }
    }

    void build(uint32_t slot, uint32_t b, uint32_t e, uint32_t depth) {
        const uint32_t count = e - b;
        AABB bounds = AABB::empty(), cbounds = AABB::empty();
        for (uint32_t i = b; i < e; ++i) {
            bounds.extend(refs_[order_[0][i]].bounds);
            cbounds.extend(refs_[order_[0][i]].centroid());
        }
        float best_cost = std::numeric_limits<float>::infinity();
        int best_axis = -1;
        uint32_t best_pos = 0;  // first index of the right side
        if (count > c_.min_leaf_size) {
            const float parent_area = bounds.half_area();
            for (int a = 0; a < 3; ++a) {
                const std::vector<uint32_t>& ord = order_[a];
                AABB acc = AABB::empty();
                for (uint32_t i = e - 1; i > b; --i) {
                    acc.extend(refs_[ord[i]].bounds);
                    area_[i] = acc.half_area();
                }
                acc = AABB::empty();
                for (uint32_t i = b; i + 1 < e; ++i) {
                    acc.extend(refs_[ord[i]].bounds);
                    // Splitting between equal centroids cannot be reproduced by a plane; skip.
                    if (refs_[ord[i]].centroid()[a] == refs_[ord[i + 1]].centroid()[a]) continue;
                    float cost = sah_split_cost(c_, parent_area, acc.half_area(), i + 1 - b, area_[i + 1], e - i - 1);
                    if (cost < best_cost) {
                        best_cost = cost;
                        best_axis = a;
                        best_pos = i + 1;
                    }
                }
            }
        }
        SplitDecision d = decide_split(c_, count, depth, best_cost);
        if (d == SplitDecision::kLeaf) {
            tree_.set_leaf(slot, b, e, bounds);
            if (c_.progress) c_.progress->add(count);
            return;
        }
        if (d == SplitDecision::kMedian) {
            best_axis = cbounds.largest_axis();
            best_pos = b + count / 2;
        }
        partition(b, e, best_axis, best_pos);
        tree_.set_interior(slot, b, best_pos, bounds);
        auto left = [&] { build(SparseTree::left_slot(slot), b, best_pos, depth + 1); };
        auto right = [&] { build(SparseTree::right_slot(slot, b, best_pos), best_pos, e, depth + 1); };
        if (count >= c_.task_threshold) {
            tbb::parallel_invoke(left, right);
        } else {
            left();
            right();
        }
    }

    std::vector<uint32_t> prim_ids() const {
        std::vector<uint32_t> ids(refs_.size());
        for (size_t i = 0; i < ids.size(); ++i) ids[i] = refs_[order_[0][i]].prim_id;
        return ids;
    }

private:
    /// Splits [b, e) of every order at position `m` of order `axis`, keeping each sorted.
    void partition(uint32_t b, uint32_t e, int axis, uint32_t m) {
        for (uint32_t i = b; i < e; ++i) goes_left_[order_[axis][i]] = i < m;
        for (int a = 0; a < 3; ++a) {
            if (a == axis) continue;
            std::vector<uint32_t>& ord = order_[a];
            uint32_t l = b, r = m;
            for (uint32_t i = b; i < e; ++i) {
                uint32_t id = ord[i];
                if (goes_left_[id])
                    ord[l++] = id;
                else
                    scratch_[r++] = id;
            }
            for (uint32_t i = m; i < e; ++i) ord[i] = scratch_[i];
        }
    }

    const SweepSahBuilder::Config& c_;
    const std::vector<PrimRef>& refs_;
    SparseTree& tree_;
    std::vector<uint32_t> order_[3];
    std::vector<uint8_t> goes_left_;  // indexed by reference; subtrees touch disjoint entries
    std::vector<float> area_;         // right-side areas, indexed by position in an order
    std::vector<uint32_t> scratch_;   // right side during a stable partition
};

}  // namespace

BuildTree SweepSahBuilder::build(const scene::TriangleMesh& mesh) const {
    std::vector<PrimRef> refs = make_prim_refs(mesh);
    BVHLAB_CHECK(!refs.empty(), "cannot build a BVH over zero triangles");
    SparseTree sparse(refs.size());
    Recursion rec(config_, refs, sparse);
    rec.build(0, 0, uint32_t(refs.size()), 0);
    return sparse.compact(rec.prim_ids());
}

}  // namespace bvhlab::accel
