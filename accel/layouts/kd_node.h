// SPDX-License-Identifier: MIT
// SAH kd-tree node and tree, shared by the builder and the traversals.
#pragma once

#include <cstdint>
#include <type_traits>
#include <vector>

#include "accel/core/aabb.h"
#include "accel/core/hd.h"

namespace bvhlab::accel {

/// 16 bytes. Interior: axis 0..2, the split plane, children at child and child + 1 (below,
/// above). Leaf: axis 3, triangles prim_indices[child .. child + count).
struct alignas(16) KdNode {
    float split;     // 4 bytes: plane position on `axis`
    uint32_t axis;   // 4 bytes: 0, 1, 2, or 3 for a leaf
    uint32_t child;  // 4 bytes: first child, or first entry in prim_indices
    uint32_t count;  // 4 bytes: leaf triangle count; total 16 bytes

    /// Leaves the node unwritten, so that a node array can be sized without a zero fill that
    /// its builder would overwrite anyway (on furball, 600 MB filled by one thread took a
    /// tenth of the kd-tree build).
    BVHLAB_HD KdNode() {}
    BVHLAB_HD KdNode(float s, uint32_t a, uint32_t c, uint32_t n) : split(s), axis(a), child(c), count(n) {}

    BVHLAB_HD bool is_leaf() const { return axis == 3; }
};
static_assert(sizeof(KdNode) == 16 && alignof(KdNode) == 16, "KdNode layout");
static_assert(std::is_trivially_copyable_v<KdNode>, "KdNode is copied as bytes (files, GPU)");

/// A kd-tree over a mesh; node 0 is the root, `bounds` the scene box. Owns its data.
struct KdTree {
    std::vector<KdNode> nodes;
    std::vector<uint32_t> prim_indices;  ///< a triangle appears in every leaf it overlaps
    AABB bounds = AABB::empty();

    size_t bytes() const { return nodes.size() * sizeof(KdNode) + prim_indices.size() * sizeof(uint32_t); }
};

}  // namespace bvhlab::accel
