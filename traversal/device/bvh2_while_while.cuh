// SPDX-License-Identifier: MIT
// Aila & Laine's while-while traversal of a BVH2 with Woop triangles ("Understanding the
// efficiency of ray traversal on GPUs", HPG 2009; the 2012 addendum for Fermi and Kepler).
// Device only: it needs warp votes and read-only loads. It visits the same nodes as the
// shared traverse_bvh2 (near child first) and tests leaves with the same Woop test, so its
// hits equal the CPU tracer's up to FMA contraction.
#pragma once

#include <cuda_runtime.h>

#include "traversal/device/bvh2_traverse.h"

namespace bvhlab::trav {

namespace ww_detail {

/// The exact form: slab_entry, shared with the CPU.
struct ExactSlabs {
    Vec3 o, inv;
    __device__ __forceinline__ ExactSlabs(Vec3 org, Vec3 inv_dir) : o(org), inv(inv_dir) {}
    __device__ __forceinline__ float entry(float lox, float hix, float loy, float hiy, float loz, float hiz,
                                           float tmin, float tmax) const {
        return slab_entry(lox, hix, loy, hiy, loz, hiz, o, inv, tmin, tmax);
    }
};

/// The FMA form. Each slab distance fma(lo, inv, -ood) differs from the exact (lo - o) * inv
/// by the rounding of ood = o * inv (at most |ood| 2^-24) plus its own relative rounding. So
/// the exit distance gets the same relative widening as slab_entry's plus 2^-22 max|ood|:
/// twice the worst absolute error of entry and exit, with a factor 2 to spare. Axes whose
/// reciprocal was clamped to 2^80 are exact (a power of two) and add nothing.
struct FmaSlabs {
    Vec3 ood, inv;
    float slack;
    __device__ __forceinline__ FmaSlabs(Vec3 org, Vec3 inv_dir, Vec3 dir) : inv(inv_dir) {
        ood = {org.x * inv.x, org.y * inv.y, org.z * inv.z};
        const float eps = 8.271806e-25f;  // safe_reciprocal's clamp
        const float ax = fabsf(dir.x) > eps ? fabsf(ood.x) : 0.0f;
        const float ay = fabsf(dir.y) > eps ? fabsf(ood.y) : 0.0f;
        const float az = fabsf(dir.z) > eps ? fabsf(ood.z) : 0.0f;
        slack = fmaxf(fmaxf(ax, ay), az) * 2.3841858e-7f;  // 2^-22
    }
    __device__ __forceinline__ float entry(float lox, float hix, float loy, float hiy, float loz, float hiz,
                                           float tmin, float tmax) const {
        const float x0 = fmaf(lox, inv.x, -ood.x), x1 = fmaf(hix, inv.x, -ood.x);
        const float y0 = fmaf(loy, inv.y, -ood.y), y1 = fmaf(hiy, inv.y, -ood.y);
        const float z0 = fmaf(loz, inv.z, -ood.z), z1 = fmaf(hiz, inv.z, -ood.z);
        const float tn = max_f(max_f(min_f(x0, x1), min_f(y0, y1)), max_f(min_f(z0, z1), tmin));
        const float tf = fmaf(min_f(min_f(max_f(x0, x1), max_f(y0, y1)), max_f(z0, z1)), 1.0000004f, slack);
        return tn <= min_f(tf, tmax) ? tn : INFINITY;
    }
};

template <bool kFma>
__device__ __forceinline__ auto make_slabs(const Ray& r, Vec3 inv) {
    if constexpr (kFma) return FmaSlabs(r.org, inv, r.dir);
    else return ExactSlabs(r.org, inv);
}

}  // namespace ww_detail

/// Closest (kAnyHit = false) or any hit of `ray`. Stack: kBvh2StackSize entries plus a
/// sentinel at the bottom, so popping needs no emptiness test. The build-time choices, each
/// measured in experiments/NOTES.md:
/// - kSpeculative: postponed leaf tests (section 4 of the paper). A lane that has found a
///   leaf keeps traversing until every active lane of its warp has one, then the warp tests
///   leaves together, so the leaf loop runs with more lanes busy.
/// - kFmaSlabs: slab distances as one FMA each, lo * inv - o * inv with o * inv computed once
///   per ray, instead of (lo - o) * inv; see FmaSlabs for why no box is lost.
template <bool kAnyHit, bool kSpeculative, bool kFmaSlabs>
__device__ __forceinline__ Hit trace_while_while(const Bvh2View& v, const Ray& ray) {
    // Above every node index, below every leaf reference as unsigned: the loop conditions
    // below are one unsigned compare each.
    constexpr int32_t kSentinel = 0x76543210;
    const Vec3 o = ray.org, d = ray.dir;
    const auto slabs = ww_detail::make_slabs<kFmaSlabs>(ray, safe_reciprocal(ray.dir));
    const float tmin = ray.tmin;
    float t_hit = ray.tmax, u_hit = 0.0f, v_hit = 0.0f;
    int32_t k_hit = -1;  // index into tris of the closest hit so far
    int32_t stack[kBvh2StackSize + 1];
    stack[0] = kSentinel;
    int sp = 0;
    int32_t node = 0;  // the root
    int32_t leaf = 0;  // a postponed leaf (< 0), or 0 for none
    const float4* nodes = reinterpret_cast<const float4*>(v.nodes);
    const float4* tris = reinterpret_cast<const float4*>(v.tris);

    while (node != kSentinel) {
        // Inner loop 1: interior nodes until this lane (or, speculative, every lane) has a leaf.
        while (uint32_t(node) < uint32_t(kSentinel)) {
            const float4 c0 = __ldg(nodes + 4 * node + 0);  // child 0: lo.x hi.x lo.y hi.y
            const float4 c1 = __ldg(nodes + 4 * node + 1);  // child 1: lo.x hi.x lo.y hi.y
            const float4 zz = __ldg(nodes + 4 * node + 2);  // lo.z hi.z of child 0, then child 1
            const int2 ch = __ldg(reinterpret_cast<const int2*>(nodes + 4 * node + 3));
            const float t0 = slabs.entry(c0.x, c0.y, c0.z, c0.w, zz.x, zz.y, tmin, t_hit);
            const float t1 = slabs.entry(c1.x, c1.y, c1.z, c1.w, zz.z, zz.w, tmin, t_hit);
            const bool hit0 = t0 != INFINITY, hit1 = t1 != INFINITY;
            if (!hit0 && !hit1) {
                node = stack[sp--];
            } else {
                // Near child first; on equal entry distances child 0, as traverse_bvh2 does.
                const bool first0 = hit0 && (!hit1 || t0 <= t1);
                node = first0 ? ch.x : ch.y;
                if (hit0 && hit1) stack[++sp] = first0 ? ch.y : ch.x;
            }
            // Postpone the first leaf found and keep looking for interior nodes.
            if (node < 0 && leaf >= 0) {
                leaf = node;
                node = stack[sp--];
            }
            if constexpr (kSpeculative) {
                if (!__any_sync(__activemask(), leaf >= 0)) break;
            } else {
                if (leaf < 0) break;
            }
        }
        // Inner loop 2: the postponed leaf, then any leaves popped right behind it.
        while (leaf < 0) {
            const uint32_t first = accel::Bvh2Node::leaf_first(leaf);
            const uint32_t end = first + accel::Bvh2Node::leaf_count(leaf);
            for (uint32_t k = first; k < end; ++k) {
                const float4 r0 = __ldg(tris + 3 * k + 0), r1 = __ldg(tris + 3 * k + 1), r2 = __ldg(tris + 3 * k + 2);
                float t, u, w;
                if (accel::WoopTriangle::intersect_rows(&r0.x, &r1.x, &r2.x, o, d, tmin, t_hit, t, u, w)) {
                    if constexpr (kAnyHit) return {int32_t(__ldg(v.tri_ids + k)), t, u, w};
                    t_hit = t;
                    u_hit = u;
                    v_hit = w;
                    k_hit = int32_t(k);
                }
            }
            leaf = node;
            if (node < 0) node = stack[sp--];
        }
    }
    if (k_hit < 0) return Hit::miss();
    return {int32_t(__ldg(v.tri_ids + k_hit)), t_hit, u_hit, v_hit};
}

/// The while-while family as a per-ray functor for launch_per_ray / launch_persistent.
template <bool kAnyHit, bool kSpeculative, bool kFmaSlabs>
struct WhileWhileTrace {
    Bvh2View view;
    __device__ __forceinline__ Hit operator()(const Ray& r) const {
        return trace_while_while<kAnyHit, kSpeculative, kFmaSlabs>(view, r);
    }
};

}  // namespace bvhlab::trav
