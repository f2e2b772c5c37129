// SPDX-License-Identifier: MIT
// An acceleration structure in its traversal layout (a BVH2 with Woop triangles, a
// compressed 8-wide BVH, or a kd-tree layout), as every tracer takes it: the CPU traversals, and the GPU kernels once
// uploaded (gpu/device_structure.h). One object per structure, whatever the layout.
#pragma once

#include <cstdint>
#include <string>

#include "accel/layouts/bvh2_node.h"
#include "accel/layouts/cwbvh_node.h"
#include "accel/layouts/kd_convert.h"

namespace bvhlab::trav {

/// The traversal layouts. A kernel traces exactly one of them.
enum class Layout : uint32_t { kBvh2 = 0, kKd = 1, kCwbvh = 2 };

/// "bvh2", "kdtree" or "cwbvh".
inline const char* layout_name(Layout layout) {
    return layout == Layout::kBvh2 ? "bvh2" : layout == Layout::kKd ? "kdtree" : "cwbvh";
}

struct Structure {
    std::string name;  ///< "bvh2/binned", "bvh2/sweep", "bvh2/sbvh", "cwbvh/<builder>" or "kdtree"
    Layout layout = Layout::kBvh2;
    accel::Bvh2 bvh2;    ///< the structure when layout == kBvh2
    accel::KdLayout kd;  ///< the structure when layout == kKd
    accel::Cwbvh cwbvh;  ///< the structure when layout == kCwbvh

    /// Stack entries a full-stack traversal needs (interior nodes on the longest path).
    uint32_t depth() const {
        return layout == Layout::kBvh2 ? bvh2.depth : layout == Layout::kKd ? kd.depth : cwbvh.depth;
    }
    size_t bytes() const {
        return layout == Layout::kBvh2 ? bvh2.bytes() : layout == Layout::kKd ? kd.bytes() : cwbvh.bytes();
    }
};

}  // namespace bvhlab::trav
