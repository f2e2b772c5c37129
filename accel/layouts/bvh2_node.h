// SPDX-License-Identifier: MIT
// Binary BVH node in the layout of Aila & Laine (2009): both children's boxes in one node,
// so one node fetch (three 16-byte loads and one 8-byte load on the GPU) decides which
// children a ray visits.
#pragma once

#include <cstdint>
#include <vector>

#include "accel/core/aabb.h"
#include "accel/core/hd.h"
#include "accel/layouts/woop_tri.h"

namespace bvhlab::accel {

/// 64 bytes. child[i] >= 0 is the index of an interior node; child[i] < 0 is a leaf, packed
/// as ~(first << 4 | (count - 1)): its triangles are tris[first .. first + count). Packing the
/// count into the reference lets the GPU kernels keep a leaf in one stack word, as Aila &
/// Laine's kernels do (they end each leaf with a sentinel triangle instead). Four bits of count
/// (leaves of up to 16 triangles) leave 27 for `first`: 2^27 (134 million) triangle references.
struct alignas(16) Bvh2Node {
    float c0_lo_x, c0_hi_x, c0_lo_y, c0_hi_y;  // 16 bytes: child 0, x and y slabs
    float c1_lo_x, c1_hi_x, c1_lo_y, c1_hi_y;  // 16 bytes: child 1, x and y slabs
    float c0_lo_z, c0_hi_z, c1_lo_z, c1_hi_z;  // 16 bytes: both children, z slabs
    int32_t child[2];                          // 8 bytes: node index, or packed leaf
    uint32_t reserved[2];                      // 8 bytes: zero; total 64 bytes

    static constexpr uint32_t kLeafCountBits = 4;
    static constexpr uint32_t kMaxLeafCount = 1u << kLeafCountBits;               ///< 16
    static constexpr uint32_t kMaxLeafFirst = (1u << (31 - kLeafCountBits)) - 1;  ///< 2^27 - 1

    /// A leaf reference; count in 1..kMaxLeafCount, first <= kMaxLeafFirst.
    BVHLAB_HD static int32_t leaf_ref(uint32_t first, uint32_t count) {
        return ~int32_t(first << kLeafCountBits | (count - 1));
    }
    BVHLAB_HD static uint32_t leaf_first(int32_t ref) { return uint32_t(~ref) >> kLeafCountBits; }
    BVHLAB_HD static uint32_t leaf_count(int32_t ref) { return (uint32_t(~ref) & (kMaxLeafCount - 1)) + 1; }
    /// Sets the box of child `slot` (0 or 1). Host and device (the GPU builders).
    BVHLAB_HD void set_child_box(int slot, const AABB& b) {
        float* xy = slot == 0 ? &c0_lo_x : &c1_lo_x;
        xy[0] = b.lo.x;
        xy[1] = b.hi.x;
        xy[2] = b.lo.y;
        xy[3] = b.hi.y;
        float* z = slot == 0 ? &c0_lo_z : &c1_lo_z;
        z[0] = b.lo.z;
        z[1] = b.hi.z;
    }
    /// The box of child `slot` (0 or 1); empty (inverted) in a root leaf's second slot.
    AABB child_box(int slot) const {
        return slot == 0 ? AABB{{c0_lo_x, c0_lo_y, c0_lo_z}, {c0_hi_x, c0_hi_y, c0_hi_z}}
                         : AABB{{c1_lo_x, c1_lo_y, c1_lo_z}, {c1_hi_x, c1_hi_y, c1_hi_z}};
    }
};
static_assert(sizeof(Bvh2Node) == 64 && alignof(Bvh2Node) == 16, "Bvh2Node layout");

/// A BVH2 ready for traversal: nodes, Woop triangles in leaf order, and for each of them the
/// id of the mesh triangle it came from. Owns its data.
struct Bvh2 {
    std::vector<Bvh2Node> nodes;
    std::vector<WoopTriangle> tris;
    std::vector<uint32_t> tri_ids;
    /// Interior nodes on the longest root-to-leaf path: a traversal that pushes at most one
    /// entry per interior node needs a stack of this many entries.
    uint32_t depth = 0;

    size_t bytes() const {
        return nodes.size() * sizeof(Bvh2Node) + tris.size() * sizeof(WoopTriangle) + tri_ids.size() * sizeof(uint32_t);
    }
};

}  // namespace bvhlab::accel
