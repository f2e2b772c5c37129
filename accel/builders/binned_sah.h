// SPDX-License-Identifier: MIT
// Binned SAH BVH builder (Wald 2007), parallel with TBB. The fast default builder.
#pragma once

#include <vector>

#include "accel/core/build_tree.h"
#include "accel/core/prim_ref.h"
#include "scene/mesh.h"

namespace bvhlab::accel {

class BinnedSahBuilder {
public:
    struct Config : BuildConfig {
        int num_bins = 32;  ///< bins per axis, 2..256
        /// Nodes with at most this many references (<= 64) are split by an exact SAH sweep
        /// over sorted centroids: cheaper than sweeping 3 x num_bins bins, and never worse.
        uint32_t sweep_threshold = 16;
        uint32_t task_threshold = 4096;              ///< subtrees at least this big become TBB tasks
        uint32_t parallel_bin_threshold = 1u << 16;  ///< nodes at least this big bin in parallel
    };

    BinnedSahBuilder() = default;
    explicit BinnedSahBuilder(const Config& config) : config_(config) {}

    /// Builds over every triangle of `mesh`. Throws bvhlab::Error on an empty mesh or bad config.
    BuildTree build(const scene::TriangleMesh& mesh) const;
    /// Builds over arbitrary references (consumed). Used by tests and by later builders.
    BuildTree build(std::vector<PrimRef> refs) const;

    const Config& config() const { return config_; }

private:
    Config config_;
};

}  // namespace bvhlab::accel
