// SPDX-License-Identifier: MIT
// Morton codes and the rules of the linear BVH's hierarchy, written once for the GPU builders
// (traversal/gpu/gpu_builder.cu) and their CPU reference (accel/builders/lbvh_reference.h), so
// that both order and split the same triangles bit for bit.
//  - The hierarchy is the binary radix tree of the sorted keys (Karras, "Maximizing Parallelism
//    in the Construction of BVHs, Octrees, and k-d Trees", HPG 2012), with the index appended to
//    equal keys.
//  - It is built bottom-up as Apetrei does ("Fast and Simple Agglomerative LBVH Construction",
//    CGVC 2014), and H-PLOC (Benthin et al., HPG 2024) after him: a node joins the neighbour
//    range whose boundary keys differ less; the second of two siblings to arrive goes on with
//    their parent. Interior node `split` (id n + split) is the one that splits its keys between
//    split and split + 1, so a node's id follows from its range alone.
#pragma once

#include <cstdint>

#include "accel/core/hd.h"
#include "accel/core/vec3.h"

namespace bvhlab::accel::morton {

/// The low 10 bits of x spread to every third bit.
BVHLAB_HD inline uint32_t spread10(uint32_t x) {
    x &= 0x3ffu;
    x = (x | (x << 16)) & 0x030000ffu;
    x = (x | (x << 8)) & 0x0300f00fu;
    x = (x | (x << 4)) & 0x030c30c3u;
    x = (x | (x << 2)) & 0x09249249u;
    return x;
}

/// The low 20 bits of x spread to every third bit.
BVHLAB_HD inline uint64_t spread20(uint64_t x) {
    x &= 0xfffffull;
    x = (x | (x << 32)) & 0x000f00000000ffffull;
    x = (x | (x << 16)) & 0x000f0000ff0000ffull;
    x = (x | (x << 8)) & 0x000f00f00f00f00full;
    x = (x | (x << 4)) & 0x00c30c30c30c30c3ull;
    x = (x | (x << 2)) & 0x0249249249249249ull;
    return x;
}

/// Cells per axis of a code of `bits` bits (30: 1024, 60: 2^20).
BVHLAB_HD inline uint32_t cells_per_axis(int bits) { return bits == 60 ? (1u << 20) : (1u << 10); }

/// The factor that maps [lo, hi] to [0, cells]: 0 for a flat axis (every point in cell 0).
BVHLAB_HD inline float axis_scale(float lo, float hi, uint32_t cells) {
    const float extent = hi - lo;
    return extent > 0.0f ? float(cells) / extent : 0.0f;
}

/// The cell of coordinate c: (c - lo) * scale, clamped to [0, cells - 1]. A subtraction and a
/// product, which no compiler fuses: host and device give the same cell.
BVHLAB_HD inline uint32_t cell(float c, float lo, float scale, uint32_t cells) {
    const float q = (c - lo) * scale;
    if (!(q > 0.0f)) return 0;
    return q >= float(cells) ? cells - 1 : uint32_t(q);
}

/// 30-bit code (10 bits per axis, x highest) of point c (a triangle box's AABB::center) in the
/// box starting at lo.
BVHLAB_HD inline uint32_t code30(Vec3 c, Vec3 lo, Vec3 scale) {
    const uint32_t n = 1u << 10;
    return spread10(cell(c.x, lo.x, scale.x, n)) << 2 | spread10(cell(c.y, lo.y, scale.y, n)) << 1 |
           spread10(cell(c.z, lo.z, scale.z, n));
}

/// 60-bit code (20 bits per axis, x highest).
BVHLAB_HD inline uint64_t code60(Vec3 c, Vec3 lo, Vec3 scale) {
    const uint32_t n = 1u << 20;
    return spread20(cell(c.x, lo.x, scale.x, n)) << 2 | spread20(cell(c.y, lo.y, scale.y, n)) << 1 |
           spread20(cell(c.z, lo.z, scale.z, n));
}

/// Apetrei's distance between sorted keys i and i + 1: their XOR above every index XOR, so
/// that equal keys are joined first, in index order.
template <typename Key>
BVHLAB_HD inline uint64_t apetrei_delta(const Key* keys, uint32_t i) {
    const uint64_t x = uint64_t(keys[i] ^ keys[i + 1]);
    return x ? x + (uint64_t(1) << 32) : uint64_t(i ^ (i + 1));
}

/// Where the node over sorted keys [left, right] (not all n >= 2 of them) goes: its parent is
/// interior node `split`, whose left child it is when `left_child` (then the parent splits
/// between `right` and `right` + 1), else its right child.
struct RadixParent {
    uint32_t split;
    bool left_child;
};

template <typename Key>
BVHLAB_HD inline RadixParent radix_parent(const Key* keys, uint32_t n, uint32_t left, uint32_t right) {
    if (left == 0 || (right != n - 1 && apetrei_delta(keys, right) < apetrei_delta(keys, left - 1)))
        return {right, true};
    return {left - 1, false};
}

}  // namespace bvhlab::accel::morton
