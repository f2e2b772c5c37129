// SPDX-License-Identifier: MIT
// SAH, EPO and size statistics of a BuildTree.
#include "accel/core/stats.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <atomic>
#include <vector>

#include "accel/core/check.h"
#include "accel/core/clip.h"
#include "accel/core/kd_cells.h"

namespace bvhlab::accel {
namespace {

/// For each node, the range of prim_indices positions its subtree covers (post-order).
std::vector<std::pair<uint32_t, uint32_t>> subtree_ranges(const BuildTree& tree) {
    std::vector<std::pair<uint32_t, uint32_t>> range(tree.nodes.size());
    // Children always come after their parent in a compacted tree, so a reverse sweep is a
    // valid post-order.
    for (size_t i = tree.nodes.size(); i-- > 0;) {
        const BuildNode& n = tree.nodes[i];
        if (n.is_leaf()) {
            range[i] = {n.first_index, n.first_index + n.prim_count};
        } else {
            const auto& l = range[n.first_index];
            const auto& r = range[n.first_index + 1];
            range[i] = {std::min(l.first, r.first), std::max(l.second, r.second)};
        }
    }
    return range;
}

/// EPO, or -1 when more than `budget` node-triangle overlap tests would be needed.
double compute_epo(const BuildTree& tree, const scene::TriangleMesh& mesh, const BuildConfig& costs, uint64_t budget,
                   ProgressCounter& progress) {
    const auto range = subtree_ranges(tree);
    // CSR list of the positions at which each triangle is referenced (one per triangle for
    // object-split trees, several for spatial splits).
    const size_t ntri = mesh.triangle_count();
    std::vector<uint32_t> offset(ntri + 1, 0), pos(tree.prim_indices.size());
    for (uint32_t id : tree.prim_indices) ++offset[id + 1];
    for (size_t i = 0; i < ntri; ++i) offset[i + 1] += offset[i];
    {
        std::vector<uint32_t> fill(offset.begin(), offset.end() - 1);
        for (uint32_t p = 0; p < tree.prim_indices.size(); ++p) pos[fill[tree.prim_indices[p]]++] = p;
    }
    auto in_subtree = [&](uint32_t tri, size_t node) {
        for (uint32_t k = offset[tri]; k < offset[tri + 1]; ++k)
            if (pos[k] >= range[node].first && pos[k] < range[node].second) return true;
        return false;
    };
    // Overlap tests are counted in batches; every thread stops once the total passes the budget.
    constexpr uint64_t kBatch = 1 << 16;
    std::atomic<uint64_t> tests{0};
    std::atomic<bool> over{false};
    // A deterministic reduce with a fixed grain keeps the float sum reproducible.
    double sum = tbb::parallel_deterministic_reduce(
        tbb::blocked_range<size_t>(0, ntri, 1024), 0.0,
        [&](const tbb::blocked_range<size_t>& r, double acc) {
            std::vector<uint32_t> stack;
            uint64_t local = 0;
            for (size_t t = r.begin(); t < r.end() && !over.load(std::memory_order_relaxed); ++t) {
                const AABB tb = mesh.triangle_bounds(t);
                const Vec3 a = mesh.vertex(t, 0), b = mesh.vertex(t, 1), c = mesh.vertex(t, 2);
                stack.assign(1, 0);
                while (!stack.empty()) {
                    uint32_t ni = stack.back();
                    stack.pop_back();
                    if (++local == kBatch) {
                        local = 0;
                        if (tests.fetch_add(kBatch, std::memory_order_relaxed) + kBatch > budget) {
                            over.store(true, std::memory_order_relaxed);
                            break;
                        }
                    }
                    const BuildNode& n = tree.nodes[ni];
                    if (!n.bounds.overlaps(tb)) continue;
                    if (!in_subtree(uint32_t(t), ni)) {
                        double area = clip_triangle(a, b, c, n.bounds).area;
                        acc += area * (n.is_leaf() ? costs.intersection_cost : costs.traversal_cost);
                    }
                    if (!n.is_leaf()) {
                        stack.push_back(n.first_index);
                        stack.push_back(n.first_index + 1);
                    }
                }
            }
            // What is left of the batch counts too (a chunk of ordinary triangles fills none).
            if (tests.fetch_add(local, std::memory_order_relaxed) + local > budget)
                over.store(true, std::memory_order_relaxed);
            progress.add(r.size());
            return acc;
        },
        [](double x, double y) { return x + y; });
    if (over.load()) return -1.0;
    double total = mesh.surface_area();
    return total > 0 ? sum / total : 0.0;
}

}  // namespace

TreeStats compute_stats(const BuildTree& tree, const scene::TriangleMesh& mesh, const BuildConfig& costs, bool with_epo,
                        uint64_t epo_budget, const ProgressFn& progress) {
    BVHLAB_CHECK(!tree.empty(), "statistics of an empty tree");
    TreeStats s;
    s.nodes = tree.nodes.size();
    s.bytes = tree.bytes();
    const double root_area = tree.nodes[0].bounds.half_area();
    std::vector<uint32_t> depth(tree.nodes.size(), 0);
    for (size_t i = 0; i < tree.nodes.size(); ++i) {
        const BuildNode& n = tree.nodes[i];
        const double rel = root_area > 0 ? n.bounds.half_area() / root_area : 0.0;
        if (n.is_leaf()) {
            ++s.leaves;
            s.references += n.prim_count;
            s.max_leaf_size = std::max(s.max_leaf_size, n.prim_count);
            s.depth = std::max(s.depth, depth[i]);
            s.sah += rel * costs.intersection_cost * n.prim_count;
        } else {
            depth[n.first_index] = depth[n.first_index + 1] = depth[i] + 1;
            s.sah += rel * costs.traversal_cost;
        }
    }
    s.mean_leaf_size = s.leaves ? double(s.references) / double(s.leaves) : 0.0;
    if (with_epo) {
        const uint64_t budget = epo_budget ? epo_budget : kEpoTestsPerTriangle * mesh.triangle_count() + (1u << 24);
        ProgressCounter counter(progress, mesh.triangle_count());
        s.epo = compute_epo(tree, mesh, costs, budget, counter);
        counter.finish();
        if (s.epo < 0)
            s.epo_skipped = "EPO skipped: it needs more than " + std::to_string(budget) +
                            " triangle-node overlap tests here (thin triangles around one vertex overlap every "
                            "node); --no-epo skips it outright";
    }
    return s;
}

KdTreeStats compute_kd_stats(const KdTree& tree, float traversal_cost, float intersection_cost) {
    KdTreeStats s;
    if (tree.nodes.empty()) return s;
    s.nodes = tree.nodes.size();
    const double root = tree.bounds.area();
    walk_kd_cells(tree, [&](uint32_t, const KdNode& n, const AABB& cell, uint32_t depth) {
        const double rel = root > 0 ? double(cell.area()) / root : 0.0;
        if (n.is_leaf()) {
            ++s.leaves;
            s.references += n.count();
            s.depth = std::max(s.depth, depth);
            s.max_leaf_size = std::max(s.max_leaf_size, n.count());
            s.sah += rel * intersection_cost * n.count();
        } else {
            s.sah += rel * traversal_cost;
        }
        return true;
    });
    return s;
}

}  // namespace bvhlab::accel
