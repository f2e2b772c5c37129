// SPDX-License-Identifier: MIT
// Binary BVH node in the layout of Aila & Laine (2009): both children's boxes in one node,
// so one node fetch (four 16-byte loads on the GPU) decides which children a ray visits.
#pragma once

#include <cstdint>
#include <vector>

#include "accel/core/hd.h"
#include "accel/layouts/woop_tri.h"

namespace bvhlab::accel {

/// 64 bytes. child[i] >= 0 is the index of an interior node; child[i] < 0 is a leaf whose
/// triangles are tris[~child[i] .. ~child[i] + count[i]).
struct alignas(16) Bvh2Node {
    float c0_lo_x, c0_hi_x, c0_lo_y, c0_hi_y;  // 16 bytes: child 0, x and y slabs
    float c1_lo_x, c1_hi_x, c1_lo_y, c1_hi_y;  // 16 bytes: child 1, x and y slabs
    float c0_lo_z, c0_hi_z, c1_lo_z, c1_hi_z;  // 16 bytes: both children, z slabs
    int32_t child[2];                          // 8 bytes
    uint32_t count[2];                         // 8 bytes: leaf triangle counts; total 64 bytes
};
static_assert(sizeof(Bvh2Node) == 64 && alignof(Bvh2Node) == 16, "Bvh2Node layout");

/// A BVH2 ready for traversal: nodes, Woop triangles in leaf order, and for each of them the
/// id of the mesh triangle it came from. Owns its data.
struct Bvh2 {
    std::vector<Bvh2Node> nodes;
    std::vector<WoopTriangle> tris;
    std::vector<uint32_t> tri_ids;

    size_t bytes() const {
        return nodes.size() * sizeof(Bvh2Node) + tris.size() * sizeof(WoopTriangle) +
               tri_ids.size() * sizeof(uint32_t);
    }
};

}  // namespace bvhlab::accel
