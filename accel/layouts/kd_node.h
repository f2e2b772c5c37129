// SPDX-License-Identifier: MIT
// SAH kd-tree node and tree, shared by the builder and the traversals.
#pragma once

#include <cstdint>
#include <cstring>
#include <type_traits>
#include <vector>

#include "accel/core/aabb.h"
#include "accel/core/hd.h"

namespace bvhlab::accel {

/// 8 bytes, as pbrt's kd-tree node. The low two bits of `bits` hold the axis, 3 for a leaf.
/// Interior: `word` is the split plane's float bits and `bits >> 2` the first child (children
/// side by side: below, above). Leaf: `word` is the first entry in prim_indices and
/// `bits >> 2` the triangle count. Children and counts are below 2^30.
struct alignas(8) KdNode {
    uint32_t word;  // 4 bytes: split plane (interior) or first prim_indices entry (leaf)
    uint32_t bits;  // 4 bytes: axis | child << 2 (interior) or 3 | count << 2 (leaf)

    static constexpr uint32_t kMaxIndex = (1u << 30) - 1;  ///< the largest child or count

    /// Leaves the node unwritten, so that a node array can be sized without a zero fill that
    /// its builder would overwrite anyway (on furball, filling its nodes on one thread, 600 MB
    /// when they were 16 bytes, had taken a tenth of the kd-tree build).
    BVHLAB_HD KdNode() {}
    BVHLAB_HD static KdNode interior(uint32_t axis, float split, uint32_t child) {
        KdNode n;
        std::memcpy(&n.word, &split, sizeof split);
        n.bits = axis | child << 2;
        return n;
    }
    BVHLAB_HD static KdNode leaf(uint32_t first, uint32_t count) {
        KdNode n;
        n.word = first;
        n.bits = 3u | count << 2;
        return n;
    }

    BVHLAB_HD bool is_leaf() const { return (bits & 3u) == 3u; }
    BVHLAB_HD uint32_t axis() const { return bits & 3u; }  ///< 0..2, or 3 for a leaf
    BVHLAB_HD float split() const {
        float f;
        std::memcpy(&f, &word, sizeof f);
        return f;
    }
    BVHLAB_HD uint32_t child() const { return bits >> 2; }  ///< interior: first child
    BVHLAB_HD uint32_t first() const { return word; }       ///< leaf: first prim_indices entry
    BVHLAB_HD uint32_t count() const { return bits >> 2; }  ///< leaf: triangle count
};
static_assert(sizeof(KdNode) == 8 && alignof(KdNode) == 8, "KdNode layout");
static_assert(std::is_trivially_copyable_v<KdNode>, "KdNode is copied as bytes (files, GPU)");

/// A kd-tree over a mesh; node 0 is the root, `bounds` the scene box. Owns its data.
struct KdTree {
    std::vector<KdNode> nodes;
    std::vector<uint32_t> prim_indices;  ///< a triangle appears in every leaf it overlaps
    AABB bounds = AABB::empty();

    size_t bytes() const { return nodes.size() * sizeof(KdNode) + prim_indices.size() * sizeof(uint32_t); }
};

}  // namespace bvhlab::accel
