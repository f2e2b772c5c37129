// SPDX-License-Identifier: MIT
// Spatial-split BVH (Stich, Friedrich & Dietrich 2009): binned object splits plus spatial
// splits that duplicate references, with exact clipped bounds and reference unsplitting,
// followed by a few passes of subtree reinsertion (accel/builders/reinsertion.h).
#pragma once

#include "accel/core/build_tree.h"
#include "scene/mesh.h"

namespace bvhlab::accel {

class SbvhBuilder {
public:
    struct Config : BuildConfig {
        int object_bins = 32;   ///< bins per axis for object splits
        int spatial_bins = 32;  ///< bins per axis for spatial splits (<= 256)
        /// Spatial splits are tried only where the best object split's children overlap by
        /// more than alpha times the root's surface area (Stich et al.'s alpha).
        float alpha = 1e-5f;
        /// A spatial split is taken only if its SAH weight is below (1 - margin) x the best
        /// object split's. Marginal spatial splits are common on finely tessellated scans and
        /// each one duplicates references for little gain: 0.1 keeps the Stanford scans under
        /// 1% duplication while furball still gets 1.77x references (experiments/NOTES.md).
        float spatial_margin = 0.1f;
        /// At most this many references in all, as a multiple of the triangle count.
        float reference_budget = 2.0f;
        uint32_t task_threshold = 4096;  ///< subtrees at least this big become TBB tasks
        /// Passes of ReinsertionOptimizer over the finished tree (0 = the plain top-down SBVH).
        int reinsertion_passes = 3;
    };

    SbvhBuilder() = default;
    explicit SbvhBuilder(const Config& config) : config_(config) {}

    /// Every triangle is referenced at least once; leaf bounds hold only the clipped parts.
    /// Throws bvhlab::Error on an empty mesh or a bad config.
    BuildTree build(const scene::TriangleMesh& mesh) const;

    const Config& config() const { return config_; }

private:
    Config config_;
};

}  // namespace bvhlab::accel
