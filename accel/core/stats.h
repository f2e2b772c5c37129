// SPDX-License-Identifier: MIT
// Tree-quality figures reported for every build: SAH cost and EPO (Aila, Karras, Laine 2013,
// "On quality metrics of bounding volume hierarchies"), sizes and leaf statistics.
#pragma once

#include <cstdint>
#include <string>

#include "accel/core/build_tree.h"
#include "accel/core/progress.h"
#include "accel/layouts/kd_node.h"
#include "scene/mesh.h"

namespace bvhlab::accel {

struct TreeStats {
    uint64_t nodes = 0;
    uint64_t leaves = 0;
    uint64_t references = 0;  ///< sum of leaf sizes (= triangles without spatial splits)
    uint32_t depth = 0;       ///< deepest leaf; the root is at depth 0
    double mean_leaf_size = 0;
    uint32_t max_leaf_size = 0;
    uint64_t bytes = 0;  ///< BuildTree nodes plus primitive indices
    /// SAH cost with the config's Ct (per interior node) and Ci (per triangle in a leaf),
    /// normalised by the root's surface area.
    double sah = 0;
    /// Sum over nodes n of C_n * (area of triangles outside n's subtree that lies inside n)
    /// / (total triangle area); C_n = Ct for interior nodes and Ci for leaves. -1 if skipped.
    double epo = -1;
    /// Why EPO was skipped although asked for ("" otherwise): its work bound was reached.
    std::string epo_skipped;
};

/// EPO's work bound, in triangle-node overlap tests per triangle. EPO visits, for each triangle,
/// every node its bounds overlap: about the tree's depth for most meshes (furball: tens), but
/// every node for a fan of thin triangles around one vertex (a 200,000-vertex polygon took
/// minutes). Beyond the bound EPO is skipped with a reason instead.
constexpr uint64_t kEpoTestsPerTriangle = 1024;

/// Computes every figure. EPO clips each triangle against the nodes its bounds overlap, in
/// parallel; pass with_epo = false to skip it on huge scenes. It stops, leaving epo = -1 and
/// epo_skipped set, after epo_budget overlap tests (0: kEpoTestsPerTriangle per triangle plus
/// 2^24). `progress` gets EPO's triangles done of the triangle count.
TreeStats compute_stats(const BuildTree& tree, const scene::TriangleMesh& mesh, const BuildConfig& costs,
                        bool with_epo = true, uint64_t epo_budget = 0, const ProgressFn& progress = {});

/// Size and quality figures of a kd-tree, from one walk over it.
struct KdTreeStats {
    uint64_t nodes = 0;
    uint64_t leaves = 0;
    uint64_t references = 0;  ///< sum of leaf sizes
    uint32_t depth = 0;       ///< deepest leaf; the root is at depth 0
    uint32_t max_leaf_size = 0;
    /// kd SAH with the given constants, normalised by the root's surface area: traversal_cost
    /// per interior node, intersection_cost per triangle reference in a leaf, each weighted by
    /// its cell's area ratio.
    double sah = 0.0;
};

KdTreeStats compute_kd_stats(const KdTree& tree, float traversal_cost, float intersection_cost);

}  // namespace bvhlab::accel
