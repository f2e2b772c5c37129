// SPDX-License-Identifier: MIT
// SAH kd-tree in O(N log N) (Wald & Havran 2006, "On building fast kd-trees for ray tracing,
// and on doing that in O(N log N)"): events sorted once, perfect splits with triangles clipped
// to the voxel, an empty-space bonus, and automatic termination by the SAH. A tree's figures
// (compute_kd_stats) and structural check (validate_kd) are beside the BVH ones in accel/core/.
#pragma once

#include <string>

#include "accel/core/stats.h"
#include "accel/core/validate.h"
#include "accel/layouts/kd_node.h"
#include "scene/mesh.h"

namespace bvhlab::accel {

class KdTreeBuilder {
public:
    /// The largest Config::small_node_size (the small-node search keeps its bounds on the stack).
    static constexpr uint32_t kMaxSmallNodeSize = 64;
    /// Defaults: Ct = 30 per traversal step, Ci = 20 per triangle, an empty-space bonus of 0.1
    /// and a depth limit of 8 + 1.3 log2(N). Ct/Ci = 1.5 and then the bonus 0.1 were measured
    /// as the fastest for this testbed's CPU kd traversal (experiments/NOTES.md, session 9):
    /// Wald & Havran's K_T = 15, K_I = 20, bonus 0.2 build trees 2-4.5x larger that trace
    /// about 5% slower.
    struct Config {
        float traversal_cost = 30.0f;
        float intersection_cost = 20.0f;
        float empty_bonus = 0.1f;  ///< cost x (1 - bonus) when one side is empty
        int max_depth = -1;        ///< -1: 8 + 1.3 log2(N), at most 64
        uint32_t task_threshold = 2048;
        /// Nodes with at most this many triangles (0..kMaxSmallNodeSize) keep no sorted events:
        /// their planes are found by counting directly, which is cheaper for so few and picks
        /// the same plane.
        uint32_t small_node_size = 64;
        /// Not part of the tree's configuration: when set, each leaf adds its reference count
        /// here as it is made (progress of the build).
        ProgressCounter* progress = nullptr;
        /// Let the small-node search use its AVX2 copy when the CPU has one (x86-64). Off:
        /// the portable copy, for comparison; both pick the same planes.
        bool use_avx2 = true;
        /// Below task_threshold (inside a subtree that one thread builds), a straddler's two
        /// clipped parts are kept and split again in the children, instead of clipping the
        /// triangle to each child's voxel anew. The bounds are the same up to double-precision
        /// rounding (the planes are applied in another order), which can move a float bound
        /// by an ulp: so with it on, the tree can differ from one built with another
        /// small_node_size or task_threshold in the last bit of a few bounds and splits. Off:
        /// every clip starts from the triangle, and the tree depends on neither (tested).
        bool reuse_clipped_polygons = true;
    };

    KdTreeBuilder() = default;
    explicit KdTreeBuilder(const Config& c) : config_(c) {}

    /// Throws bvhlab::Error on an empty mesh or a bad config.
    KdTree build(const scene::TriangleMesh& mesh) const;

    const Config& config() const { return config_; }
    /// The depth limit for n triangles.
    int max_depth_for(size_t n) const;

private:
    Config config_;
};

/// "" when every value of `c` is in its range, else one line naming the first that is not
/// (kd_ct, kd_ci, kd_bonus, kd_max_depth, as structure specs name them).
std::string kd_config_problem(const KdTreeBuilder::Config& c);

}  // namespace bvhlab::accel
