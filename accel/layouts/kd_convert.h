// SPDX-License-Identifier: MIT
// KdTree -> KdLayout: the tree with the Woop triangles its traversals test, like
// convert_to_bvh2 for BVHs. The layout owns everything; the CPU and GPU tracers share it.
#pragma once

#include <vector>

#include "accel/layouts/kd_node.h"
#include "accel/layouts/woop_tri.h"
#include "scene/mesh.h"

namespace bvhlab::accel {

/// A kd-tree ready for traversal. Leaves reference mesh triangle ids through
/// tree.prim_indices, and tris holds one Woop triangle per mesh triangle (a kd-tree lists a
/// triangle in several leaves, 3-7x on the benchmark scenes, so triangles are not copied
/// into leaf order as in the BVH2 layout: on furball that would be 0.97 GB instead of 131 MB).
struct KdLayout {
    KdTree tree;
    std::vector<WoopTriangle> tris;
    /// Interior nodes on the longest root-to-leaf path: the stack a full-stack traversal needs.
    uint32_t depth = 0;

    size_t bytes() const { return tree.bytes() + tris.size() * sizeof(WoopTriangle); }
};

/// Takes over `tree` (built over `mesh`) and adds the Woop triangles and the depth.
KdLayout convert_to_kd_layout(KdTree tree, const scene::TriangleMesh& mesh);

}  // namespace bvhlab::accel
