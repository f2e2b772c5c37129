// SPDX-License-Identifier: MIT
// Traversal of a compressed 8-wide BVH (Ylitie, Karras & Laine, HPG 2017, section 4), written
// once for host and device: the CPU reference (`--device cpu --kernel cwbvh`) and the GPU
// kernel run this code, so they visit the same nodes and return the same hits.
//
// The ray keeps two groups: a node group (a node's interior children that the ray entered, as
// hit-mask bits 24..31 in octant order, with the parent's child base and interior mask) and a
// triangle group (the triangles of the leaves it entered, bits 0..23). Each step takes the
// nearest interior child of the node group (the highest bit: slots are octant-ordered, see
// CwbvhNode), pushes what is left of the group, fetches that child and tests its eight
// boxes into new groups; then the triangle group is tested. The stack holds node groups, at
// most one per level.
#pragma once

#include <cstdint>
#include <cstring>

#include "accel/core/bits.h"
#include "accel/core/build_tree.h"
#include "accel/core/hd.h"
#include "accel/layouts/cwbvh_node.h"
#include "traversal/device/bvh2_traverse.h"
#include "traversal/device/ray.h"

namespace bvhlab::trav {

/// Stack entries of the CWBVH traversal: trees deeper than this (Cwbvh::depth) are refused
/// before any ray is traced. A wide level takes at least one binary level, and splitting
/// leaves of up to 64 references into leaves of 3 adds at most 5, so the collapse of any
/// builder's tree is at most kMaxTreeDepth + 5 wide nodes deep.
constexpr int kCwbvhStackSize = int(accel::kMaxTreeDepth) + 8;
static_assert(kCwbvhStackSize >= int(accel::kMaxTreeDepth) + 5, "the CWBVH stack must hold any collapsed tree");

/// A CWBVH layout as traversal sees it: plain pointers, host or device memory.
struct CwbvhView {
    const accel::CwbvhNode* nodes;
    const accel::WoopTriangle* tris;  ///< the triangles with CwTris::kWoop, else null
    const uint32_t* tri_ids;
    const accel::VertexTriangle* vtris = nullptr;  ///< the triangles with CwTris::kVertices, else null
    uint32_t one = accel::kCwbvhUnpackOne;         ///< see cwbvh_unpack: a kernel parameter, not a literal
};

namespace cw_detail {

/// The node as 20 words, read as five 16-byte loads on the device.
BVHLAB_HD BVHLAB_FORCEINLINE void load_node(const accel::CwbvhNode* n, uint32_t (&w)[20]) {
#if defined(__CUDA_ARCH__)
    const uint4* p = reinterpret_cast<const uint4*>(n);
    BVHLAB_UNROLL
    for (int i = 0; i < 5; ++i) {
        const uint4 v = __ldg(p + i);
        w[4 * i] = v.x;
        w[4 * i + 1] = v.y;
        w[4 * i + 2] = v.z;
        w[4 * i + 3] = v.w;
    }
#else
    std::memcpy(w, n, sizeof w);
#endif
}
static_assert(sizeof(accel::CwbvhNode) == 20 * sizeof(uint32_t), "five 16-byte loads");

/// Word indices in the node (see CwbvhNode).
constexpr int kWordExponents = 3, kWordChildBase = 4, kWordTriBase = 5, kWordMeta = 6, kWordQlo = 8, kWordQhi = 14;

/// What a ray needs per axis, once.
struct RayAxes {
    Vec3 o;
    float inv[3];
    bool neg[3];
    uint32_t octant;  // bit k set when the direction's component k is not negative
};

/// Tests the node's eight child boxes within [tmin, tmax]. Returns the hit mask: for each
/// slot entered, (meta >> 5) << (meta & 31), with interior slots moved to bit 24 + (s ^ octant).
/// `leaves_hit` counts the leaf slots entered.
///
/// Plane distances: slot s's plane on axis k is p + q * 2^e. With f = 1 + q * 2^-15 (the byte
/// unpacked, exactly) and sc = 2^e * 2^15 * inv (a power-of-two scaling, exact), the distance
/// (p + q 2^e - o) * inv is f * sc + orig with orig = (p - o) * inv - sc: one FMA per plane.
/// Robustness, as FmaSlabs: orig carries at most 2^-24 (|orig| + |sc|) from rounding p - o and
/// the FMA that makes it, so near planes are lowered and far planes raised by
/// 2^-22 (|orig| + |sc|), and far planes are widened by 1 + 2^-21 for their own rounding. The
/// |sc| term is 1/128 of one quantisation step.
BVHLAB_HD BVHLAB_FORCEINLINE uint32_t intersect_children(const uint32_t (&w)[20], const RayAxes& r, float tmin,
                                                         float tmax, uint32_t one, uint32_t& leaves_hit) {
    constexpr float kWiden = 1.0000005f;  // 1 + 2^-21
    float sc_near[3], sc_far[3], off_near[3], off_far[3];
    uint32_t qn[3][2], qf[3][2];
    BVHLAB_UNROLL
    for (int k = 0; k < 3; ++k) {
        const float p = float_from_bits(w[k]);
        const float sc = accel::cwbvh_scale((w[kWordExponents] >> (8 * k)) & 0xFFu) * 32768.0f * r.inv[k];
        const float orig = fmaf(p - r.o[k], r.inv[k], -sc);
        const float slack = (fabsf(orig) + fabsf(sc)) * 2.3841858e-7f;  // 2^-22
        sc_near[k] = sc;
        sc_far[k] = sc * kWiden;
        off_near[k] = orig - slack;
        off_far[k] = (orig + slack) * kWiden;
        // The near plane of a positive axis is the lower one.
        BVHLAB_UNROLL
        for (int h = 0; h < 2; ++h) {
            const uint32_t lo = w[kWordQlo + 2 * k + h], hi = w[kWordQhi + 2 * k + h];
            qn[k][h] = r.neg[k] ? hi : lo;
            qf[k][h] = r.neg[k] ? lo : hi;
        }
    }
    // Each slot's hit-mask bits and shift, four slots per word (Ylitie et al.'s trick): the
    // shift is meta & 31, with the octant folded into interior slots; the bits are meta >> 5.
    // Per node this costs ~10 word operations instead of ~5 per slot.
    const uint32_t imask = w[kWordExponents] >> 24, octant4 = r.octant * 0x01010101u;
    uint32_t shift4[2], bits4[2];
    BVHLAB_UNROLL
    for (int h = 0; h < 2; ++h) {
        const uint32_t meta4 = w[kWordMeta + h];
        const uint32_t inner4 = ((((imask >> (4 * h)) & 0xFu) * 0x00204081u) & 0x01010101u) * 0xFFu;
        shift4[h] = (meta4 ^ (octant4 & inner4)) & 0x1F1F1F1Fu;
        bits4[h] = (meta4 >> 5) & 0x07070707u;
    }
    uint32_t hits = 0, leaves = 0;
    BVHLAB_UNROLL
    for (uint32_t s = 0; s < 8; ++s) {
        const uint32_t h = s >> 2, b = s & 3;
        const float nx = fmaf(accel::cwbvh_unpack(qn[0][h], b, one), sc_near[0], off_near[0]);
        const float ny = fmaf(accel::cwbvh_unpack(qn[1][h], b, one), sc_near[1], off_near[1]);
        const float nz = fmaf(accel::cwbvh_unpack(qn[2][h], b, one), sc_near[2], off_near[2]);
        const float fx = fmaf(accel::cwbvh_unpack(qf[0][h], b, one), sc_far[0], off_far[0]);
        const float fy = fmaf(accel::cwbvh_unpack(qf[1][h], b, one), sc_far[1], off_far[1]);
        const float fz = fmaf(accel::cwbvh_unpack(qf[2][h], b, one), sc_far[2], off_far[2]);
        const float tn = max_f(max_f(nx, ny), max_f(nz, tmin));
        const float tf = min_f(min_f(fx, fy), min_f(fz, tmax));
        if (tn <= tf) {  // an empty slot has no bits
            const uint32_t bits = (bits4[h] >> (8 * b)) & 7u;
            hits |= bits << ((shift4[h] >> (8 * b)) & 31u);
            leaves += bits != 0 && !((imask >> s) & 1u);
        }
    }
    leaves_hit += leaves;
    return hits;
}

/// Intersects triangle k. Woop: three 16-byte read-only loads on the device, the shared Woop
/// test. Vertices: nine 4-byte read-only loads (36-byte records are only 4-byte aligned) and
/// Moller-Trumbore.
template <bool kVertexTris>
BVHLAB_HD BVHLAB_FORCEINLINE bool intersect_tri(const CwbvhView& view, uint32_t k, Vec3 o, Vec3 d, float tmin,
                                                float tmax, float& t, float& u, float& v) {
#if defined(__CUDA_ARCH__)
    if constexpr (kVertexTris) {
        const float* p = view.vtris[k].f;
        float f[9];
        BVHLAB_UNROLL
        for (int i = 0; i < 9; ++i) f[i] = __ldg(p + i);
        return accel::VertexTriangle::intersect_values(f, o, d, tmin, tmax, t, u, v);
    } else {
        const float4* p = reinterpret_cast<const float4*>(view.tris + k);
        const float4 r0 = __ldg(p), r1 = __ldg(p + 1), r2 = __ldg(p + 2);
        return accel::WoopTriangle::intersect_rows(&r0.x, &r1.x, &r2.x, o, d, tmin, tmax, t, u, v);
    }
#else
    if constexpr (kVertexTris)
        return view.vtris[k].intersect(o, d, tmin, tmax, t, u, v);
    else
        return view.tris[k].intersect(o, d, tmin, tmax, t, u, v);
#endif
}

}  // namespace cw_detail

/// The node-group stack: base indices and group bits, kCwbvhStackSize entries.
struct CwbvhStack {
    uint32_t base[kCwbvhStackSize];
    uint32_t bits[kCwbvhStackSize];
};

/// A ray in flight through a CWBVH: what traverse_cwbvh keeps between steps, so that a kernel
/// can hand a finished lane a new ray between steps (dynamic fetch).
struct CwbvhState {
    cw_detail::RayAxes axes;  // the origin among them
    Vec3 d;
    float tmin, t_hit, u_hit, v_hit;
    int32_t k_hit;
    uint32_t group_base, group_bits;  // node group: base, interior hits (bits 24..31) | imask
    int sp;
};

namespace cw_detail {

/// `s`'s ray: origin o, direction d, and what the box tests need per axis.
BVHLAB_HD BVHLAB_FORCEINLINE void set_ray(CwbvhState& s, Vec3 o, Vec3 d) {
    const Vec3 inv = safe_reciprocal(d);
    s.d = d;
    s.axes.o = o;
    s.axes.inv[0] = inv.x, s.axes.inv[1] = inv.y, s.axes.inv[2] = inv.z;
    s.axes.octant = 0;
    for (int k = 0; k < 3; ++k) {
        s.axes.neg[k] = s.axes.inv[k] < 0.0f;
        s.axes.octant |= uint32_t(!s.axes.neg[k]) << k;
    }
}

/// The node visit of a step: the nearest interior child left in `s`'s node group (the highest
/// bit: slots are octant-ordered, see CwbvhNode) is fetched into `w` and its eight boxes
/// tested; what is left of the group goes to push(base, bits) first. `s`'s node group becomes
/// the child's interior hits; returns the hit mask (leaf slots in bits 0..23).
template <class Push>
BVHLAB_HD BVHLAB_FORCEINLINE uint32_t visit_nearest(const accel::CwbvhNode* nodes, uint32_t one, CwbvhState& s,
                                                    uint32_t (&w)[20], TraversalCounters* counters, Push&& push) {
    const uint32_t bit = highest_bit(s.group_bits & 0xFF000000u);
    s.group_bits &= ~(1u << bit);
    const uint32_t slot = (bit - accel::CwbvhNode::kInteriorBit) ^ s.axes.octant;
    const uint32_t node = s.group_base + popc32(s.group_bits & ((1u << slot) - 1u) & 0xFFu);
    if (s.group_bits & 0xFF000000u) push(s.group_base, s.group_bits);
    load_node(nodes + node, w);
    uint32_t leaves = 0;
    const uint32_t hits = intersect_children(w, s.axes, s.tmin, s.t_hit, one, leaves);
    if (counters) {
        ++counters->nodes;
        counters->leaves += leaves;
    }
    s.group_base = w[kWordChildBase];
    s.group_bits = (hits & 0xFF000000u) | (w[kWordExponents] >> 24);
    return hits;
}

/// Tests the triangles of `bits` (leaf-slot bits 0..23, numbered from `base`) against `s`'s ray
/// within its closest t, which each hit lowers. Returns the last triangle hit, or -1; an
/// any-hit query (kAnyHit) returns the first.
template <bool kAnyHit, bool kVertexTris>
BVHLAB_HD BVHLAB_FORCEINLINE int32_t test_triangles(const CwbvhView& v, uint32_t base, uint32_t bits, CwbvhState& s,
                                                    TraversalCounters* counters) {
    int32_t found = -1;
    while (bits) {
        const uint32_t k = base + lowest_bit(bits);
        bits &= bits - 1u;
        if (counters) ++counters->tri_tests;
        float t, u, vv;
        if (intersect_tri<kVertexTris>(v, k, s.axes.o, s.d, s.tmin, s.t_hit, t, u, vv)) {
            s.t_hit = t;
            s.u_hit = u;
            s.v_hit = vv;
            found = int32_t(k);
            if (kAnyHit) break;
        }
    }
    return found;
}

}  // namespace cw_detail

/// Starts `ray`: the root as the one interior child (slot 0) of a virtual parent whose
/// children start at node 0.
BVHLAB_HD BVHLAB_FORCEINLINE void cwbvh_start(CwbvhState& s, const Ray& ray) {
    cw_detail::set_ray(s, ray.org, ray.dir);
    s.tmin = ray.tmin;
    s.t_hit = ray.tmax;
    s.u_hit = s.v_hit = 0.0f;
    s.k_hit = -1;
    s.group_base = 0;
    s.group_bits = (1u << (accel::CwbvhNode::kInteriorBit + s.axes.octant)) | 1u;
    s.sp = 0;
}

/// Whether the ray has finished (no node group left to visit).
BVHLAB_HD BVHLAB_FORCEINLINE bool cwbvh_done(const CwbvhState& s) { return !(s.group_bits & 0xFF000000u); }

/// One step: the nearest interior child left in the node group (the highest bit: slots are
/// octant-ordered, see CwbvhNode) is fetched and its eight boxes tested, what is left of the
/// group waits on the stack, then the triangles of the leaves entered are tested. When the
/// group is empty the next one is popped; the ray is done when none is left.
template <bool kAnyHit, bool kVertexTris = false>
BVHLAB_HD BVHLAB_FORCEINLINE void cwbvh_step(const CwbvhView& v, CwbvhState& s, CwbvhStack& stack,
                                             TraversalCounters* counters) {
    uint32_t w[20];
    const uint32_t hits = cw_detail::visit_nearest(v.nodes, v.one, s, w, counters, [&](uint32_t base, uint32_t bits) {
        stack.base[s.sp] = base;
        stack.bits[s.sp++] = bits;
    });
    const int32_t k =
        cw_detail::test_triangles<kAnyHit, kVertexTris>(v, w[cw_detail::kWordTriBase], hits & 0x00FFFFFFu, s, counters);
    if (k >= 0) {
        s.k_hit = k;
        if (kAnyHit) {  // any hit ends the ray
            s.group_bits = 0;
            return;
        }
    }
    if (!(s.group_bits & 0xFF000000u) && s.sp > 0) {
        --s.sp;
        s.group_base = stack.base[s.sp];
        s.group_bits = stack.bits[s.sp];
    }
}

/// The hit of a finished ray.
BVHLAB_HD BVHLAB_FORCEINLINE Hit cwbvh_result(const CwbvhView& v, const CwbvhState& s) {
    if (s.k_hit < 0) return Hit::miss();
    return {int32_t(v.tri_ids[s.k_hit]), s.t_hit, s.u_hit, s.v_hit};
}

/// Closest hit (kAnyHit = false) or any hit (kAnyHit = true) of `ray`, on a CWBVH whose
/// triangles are vertex triples (kVertexTris) or Woop maps.
template <bool kAnyHit, bool kVertexTris = false>
BVHLAB_HD inline Hit traverse_cwbvh(const CwbvhView& v, const Ray& ray, TraversalCounters* counters = nullptr) {
    CwbvhState s;
    CwbvhStack stack;
    cwbvh_start(s, ray);
    while (!cwbvh_done(s)) cwbvh_step<kAnyHit, kVertexTris>(v, s, stack, counters);
    return cwbvh_result(v, s);
}

}  // namespace bvhlab::trav
