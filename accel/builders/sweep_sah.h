// SPDX-License-Identifier: MIT
// Full-sweep SAH BVH builder: evaluates every object split between sorted centroids on all
// three axes (MacDonald & Booth 1990). The quality reference for the binned builder.
#pragma once

#include "accel/core/build_tree.h"
#include "scene/mesh.h"

namespace bvhlab::accel {

class SweepSahBuilder {
public:
    struct Config : BuildConfig {
        uint32_t task_threshold = 4096;  ///< subtrees at least this big become TBB tasks
    };

    SweepSahBuilder() = default;
    explicit SweepSahBuilder(const Config& config) : config_(config) {}

    /// O(N log N): the three centroid orders are sorted once and kept sorted by stable
    /// partitions. Throws bvhlab::Error on an empty mesh.
    BuildTree build(const scene::TriangleMesh& mesh) const;

    const Config& config() const { return config_; }

private:
    Config config_;
};

}  // namespace bvhlab::accel
