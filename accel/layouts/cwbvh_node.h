// SPDX-License-Identifier: MIT
// The compressed 8-wide BVH node of Ylitie, Karras & Laine (HPG 2017, figure 2): 80 bytes
// for eight children, their boxes quantised to 8 bits per plane against the node's origin
// and per-axis power-of-two scale. Written once for host and device.
#pragma once

#include <cstdint>
#include <vector>

#include "accel/core/bits.h"
#include "accel/core/hd.h"
#include "accel/layouts/vertex_tri.h"
#include "accel/layouts/woop_tri.h"

namespace bvhlab::accel {

/// Child slot s of a node decodes on axis k to [p_k + qlo_k[s] * 2^e_k, p_k + qhi_k[s] * 2^e_k],
/// which contains the exact child box (conservative quantisation; tested).
///
/// meta[s] says what slot s holds:
/// - 0: nothing (its quantised box is also empty: qlo = 255 > qhi = 0);
/// - an interior node: 0b001 << 5 | (24 + s); the node is nodes[child_base + the number of
///   interior slots below s] (imask bit s is set);
/// - a leaf of c = 1..3 triangles: unary(c) << 5 | offset, unary = 0b001, 0b011, 0b111; its
///   triangles are tris[tri_base + offset .. + c), offset + c <= 24.
/// So a hit slot contributes (meta >> 5) << (meta & 31) to a 32-bit hit mask: triangle bits
/// 0..23, interior-child bits 24..31 (Ylitie et al.'s encoding).
///
/// Slots are assigned by octant: the child whose centroid lies furthest in the direction
/// (s & 1 ? +x : -x, s & 2 ? +y : -y, s & 4 ? +z : -z) from the node's centre takes slot s, so a
/// ray whose direction has sign bits m (bit k set for a non-negative component) meets the
/// children roughly in decreasing order of s ^ m.
struct alignas(16) CwbvhNode {
    float p[3];           // 12 bytes: origin (the node box's lower corner)
    uint8_t e[3];         // 3 bytes: per-axis scale exponents, biased by 127
    uint8_t imask;        // 1 byte: bit s set when slot s holds an interior node
    uint32_t child_base;  // 4 bytes: index of the first interior child
    uint32_t tri_base;    // 4 bytes: index of the first triangle of the leaves
    uint8_t meta[8];      // 8 bytes
    uint8_t qlo[3][8];    // 24 bytes: quantised lower planes, axis-major
    uint8_t qhi[3][8];    // 24 bytes: quantised upper planes; total 80 bytes

    static constexpr uint8_t kInteriorMeta = 1u << 5;
    static constexpr uint32_t kInteriorBit = 24;
    BVHLAB_HD static uint8_t interior_meta(uint32_t slot) { return uint8_t(kInteriorMeta | (kInteriorBit + slot)); }
    BVHLAB_HD static uint8_t leaf_meta(uint32_t offset, uint32_t count) {
        return uint8_t(((1u << count) - 1u) << 5 | offset);
    }
};
static_assert(sizeof(CwbvhNode) == 80 && alignof(CwbvhNode) == 16, "CwbvhNode layout");

/// A scale exponent's factor 2^(e - 127) as a float (e in 1..254).
BVHLAB_HD BVHLAB_FORCEINLINE float cwbvh_scale(uint32_t biased_exponent) {
    return float_from_bits(biased_exponent << 23);
}

/// Byte `byte` (0..3) of `word` as the float 1 + q * 2^-15: one byte permute on the device
/// (against an I2F conversion at a quarter of the FMA rate). The traversal folds the 1 and the
/// 2^15 into per-node constants. `one` must be 0x3F800000; the kernels pass it in as a
/// value that ptxas cannot fold (CwbvhView::one): with a literal it made the constant the
/// permute's immediate and rebuilt the selector in a register before almost every permute
/// (~30 extra instructions per node in the SASS).
BVHLAB_HD BVHLAB_FORCEINLINE float cwbvh_unpack(uint32_t word, uint32_t byte, uint32_t one) {
#if defined(__CUDA_ARCH__)
    return __uint_as_float(__byte_perm(word, one, 0x7604u | (byte << 4)));
#else
    return float_from_bits(one | ((word >> (8 * byte)) & 0xFFu) << 8);
#endif
}

/// The `one` of cwbvh_unpack.
constexpr uint32_t kCwbvhUnpackOne = 0x3F800000u;

/// How a CWBVH stores its leaves' triangles (--cw-tris): Woop's 48-byte maps (three 16-byte
/// loads, the cheaper test) or 36-byte vertex triples (0.75x the bytes, nine 4-byte loads and
/// Moller-Trumbore). experiments/NOTES.md has the measured choice.
enum class CwTris : uint32_t { kWoop = 0, kVertices = 1 };

/// A CWBVH ready for traversal: nodes (root at 0), triangles in leaf order (in `tris` or
/// `vtris`, as `tri_format` says; the other is empty), and each one's mesh triangle id.
/// Owns its data.
struct Cwbvh {
    std::vector<CwbvhNode> nodes;
    std::vector<WoopTriangle> tris;
    std::vector<VertexTriangle> vtris;
    std::vector<uint32_t> tri_ids;
    CwTris tri_format = CwTris::kWoop;
    uint32_t depth = 0;  ///< wide nodes on the longest root-to-leaf path

    size_t bytes() const {
        return nodes.size() * sizeof(CwbvhNode) + tris.size() * sizeof(WoopTriangle) +
               vtris.size() * sizeof(VertexTriangle) + tri_ids.size() * sizeof(uint32_t);
    }
};

}  // namespace bvhlab::accel
