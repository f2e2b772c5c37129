// SPDX-License-Identifier: MIT
// An acceleration structure in its traversal layout (a BVH2 with Woop triangles, a
// compressed 8-wide BVH, or a kd-tree layout), as every tracer takes it: the CPU traversals, and the GPU kernels once
// uploaded (gpu/device_structure.h). One object per structure, whatever the layout.
#pragma once

#include <algorithm>
#include <cstdint>
#include <string>

#include "accel/layouts/bvh2_node.h"
#include "accel/layouts/cwbvh_node.h"
#include "accel/layouts/kd_convert.h"
#include "accel/layouts/two_level.h"

namespace bvhlab::trav {

/// The traversal layouts. A kernel traces exactly one of them.
/// kTwoLevel has BVH2 BLAS, kTwoLevelCwbvh compressed 8-wide ones (both a BVH2 TLAS).
enum class Layout : uint32_t { kBvh2 = 0, kKd = 1, kCwbvh = 2, kTwoLevel = 3, kTwoLevelCwbvh = 4 };

/// "bvh2", "kdtree", "cwbvh", "two-level" or "two-level-cwbvh".
inline const char* layout_name(Layout layout) {
    return layout == Layout::kBvh2       ? "bvh2"
           : layout == Layout::kKd       ? "kdtree"
           : layout == Layout::kCwbvh    ? "cwbvh"
           : layout == Layout::kTwoLevel ? "two-level"
                                         : "two-level-cwbvh";
}

/// Whether `layout` is one of the two-level layouts (Structure::two_level).
inline bool is_two_level(Layout layout) { return layout == Layout::kTwoLevel || layout == Layout::kTwoLevelCwbvh; }

struct Structure {
    /// "bvh2/binned", "bvh2/sweep", "bvh2/sbvh", "cwbvh/<builder>", "kdtree",
    /// "two-level/<builder>" (BVH2 BLAS by that builder under a binned TLAS), or
    /// "two-level-cwbvh/<builder>" (the same BLAS collapsed to CWBVHs)
    std::string name;
    Layout layout = Layout::kBvh2;
    accel::Bvh2 bvh2;              ///< the structure when layout == kBvh2
    accel::KdLayout kd;            ///< the structure when layout == kKd
    accel::Cwbvh cwbvh;            ///< the structure when layout == kCwbvh
    accel::TwoLevelBvh two_level;  ///< the structure of both two-level layouts (hits: scene-wide ids)

    /// Stack entries a full-stack traversal needs (interior nodes on the longest path).
    /// For a two-level BVH: the deeper of its TLAS and BLAS stacks (each level has its own).
    uint32_t depth() const {
        return layout == Layout::kBvh2    ? bvh2.depth
               : layout == Layout::kKd    ? kd.depth
               : layout == Layout::kCwbvh ? cwbvh.depth
                                          : std::max(two_level.tlas_depth(), two_level.blas_depth());
    }
    size_t bytes() const {
        return layout == Layout::kBvh2    ? bvh2.bytes()
               : layout == Layout::kKd    ? kd.bytes()
               : layout == Layout::kCwbvh ? cwbvh.bytes()
                                          : two_level.bytes();
    }
};

}  // namespace bvhlab::trav
