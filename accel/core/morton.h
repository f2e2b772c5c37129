// SPDX-License-Identifier: MIT
// Morton codes and the rules of the linear BVH's hierarchy, written once for the GPU builders
// (traversal/gpu/gpu_builder.cu) and their CPU reference (accel/builders/lbvh_reference.h), so
// that both order and split the same triangles bit for bit.
//  - Karras, "Maximizing Parallelism in the Construction of BVHs, Octrees, and k-d Trees"
//    (HPG 2012): each interior node finds its key range and split from the sorted keys alone.
//  - Apetrei, "Fast and Simple Agglomerative LBVH Construction" (CGVC 2014), as H-PLOC
//    (Benthin et al., HPG 2024) uses it: a node joins the neighbour range whose boundary keys
//    differ less.
#pragma once

#include <cstdint>

#include "accel/core/hd.h"
#include "accel/core/vec3.h"

namespace bvhlab::accel::morton {

/// Leading zero bits of a 32- or 64-bit key (its width for 0).
BVHLAB_HD inline int clz(uint32_t x) {
#if defined(__CUDA_ARCH__)
    return __clz(x);
#else
    return x ? __builtin_clz(x) : 32;
#endif
}

BVHLAB_HD inline int clz(uint64_t x) {
#if defined(__CUDA_ARCH__)
    return __clzll(x);
#else
    return x ? __builtin_clzll(x) : 64;
#endif
}

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

/// Karras's delta: the length of the common prefix of sorted keys i and j, with the index
/// appended to equal keys so that every key is distinct; -1 for j outside [0, n).
template <typename Key>
BVHLAB_HD inline int karras_delta(const Key* keys, int64_t n, int64_t i, int64_t j) {
    if (j < 0 || j >= n) return -1;
    const Key x = keys[i] ^ keys[j];
    if (x) return clz(x);
    return int(8 * sizeof(Key)) + clz(uint32_t(i) ^ uint32_t(j));
}

/// The children of Karras's interior node i (0 <= i < n - 1) over n >= 2 sorted keys, as node
/// ids: leaf k is k, interior node k is n + k (so the root is n).
template <typename Key>
BVHLAB_HD inline void karras_children(const Key* keys, int64_t n, int64_t i, uint32_t& left, uint32_t& right) {
    const int d = karras_delta(keys, n, i, i + 1) - karras_delta(keys, n, i, i - 1) > 0 ? 1 : -1;
    const int delta_min = karras_delta(keys, n, i, i - d);
    int64_t l_max = 2;
    while (karras_delta(keys, n, i, i + l_max * d) > delta_min) l_max *= 2;
    int64_t l = 0;
    for (int64_t t = l_max / 2; t >= 1; t /= 2)
        if (karras_delta(keys, n, i, i + (l + t) * d) > delta_min) l += t;
    const int64_t j = i + l * d;
    const int delta_node = karras_delta(keys, n, i, j);
    int64_t s = 0;
    for (int64_t div = 2;; div *= 2) {
        const int64_t t = (l + div - 1) / div;
        if (karras_delta(keys, n, i, i + (s + t) * d) > delta_node) s += t;
        if (t <= 1) break;
    }
    const int64_t gamma = i + s * d + (d < 0 ? -1 : 0);
    const int64_t lo = i < j ? i : j, hi = i < j ? j : i;
    left = uint32_t(lo == gamma ? gamma : n + gamma);
    right = uint32_t(hi == gamma + 1 ? gamma + 1 : n + gamma + 1);
}

/// Apetrei's distance between sorted keys i and i + 1: their XOR above every index XOR, so
/// that equal keys are joined first, in index order.
template <typename Key>
BVHLAB_HD inline uint64_t apetrei_delta(const Key* keys, uint32_t i) {
    const uint64_t x = uint64_t(keys[i] ^ keys[i + 1]);
    return x ? x + (uint64_t(1) << 32) : uint64_t(i ^ (i + 1));
}

}  // namespace bvhlab::accel::morton
