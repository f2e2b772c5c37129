// SPDX-License-Identifier: MIT
// SAH kd-tree in O(N log N) (Wald & Havran 2006, "On building fast kd-trees for ray tracing,
// and on doing that in O(N log N)"): events sorted once, perfect splits with triangles clipped
// to the voxel, an empty-space bonus, and automatic termination by the SAH.
#pragma once

#include "accel/core/mesh.h"
#include "accel/layouts/kd_node.h"

namespace bvhlab::accel {

class KdTreeBuilder {
public:
    /// Defaults follow Wald & Havran: Ct = 15 per traversal step, Ci = 20 per triangle (their
    /// K_T and K_I), an empty-space bonus of 0.2, and a depth limit of 8 + 1.3 log2(N).
    struct Config {
        float traversal_cost = 15.0f;
        float intersection_cost = 20.0f;
        float empty_bonus = 0.2f;  ///< cost x (1 - bonus) when one side is empty
        int max_depth = -1;        ///< -1: 8 + 1.3 log2(N), at most 64
        uint32_t task_threshold = 2048;
    };

    KdTreeBuilder() = default;
    explicit KdTreeBuilder(const Config& c) : config_(c) {}

    /// Throws bvhlab::Error on an empty mesh or a bad config.
    KdTree build(const TriangleMesh& mesh) const;

    const Config& config() const { return config_; }
    /// The depth limit for n triangles.
    int max_depth_for(size_t n) const;

private:
    Config config_;
};

/// kd SAH of a tree with the given constants, normalised by the root's surface area:
/// Ct per interior node, Ci per triangle reference in a leaf, each weighted by area ratio.
double kd_sah(const KdTree& tree, const KdTreeBuilder::Config& c);

}  // namespace bvhlab::accel
