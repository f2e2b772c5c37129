// SPDX-License-Identifier: MIT
// Aila & Laine's while-while traversal of a BVH2 with Woop triangles ("Understanding the
// efficiency of ray traversal on GPUs", HPG 2009; the 2012 addendum for Fermi and Kepler).
// Device only: it needs warp votes and read-only loads. It visits the same nodes as the
// shared traverse_bvh2 (near child first) and tests leaves with the same Woop test, so its
// hits equal the CPU tracer's up to FMA contraction.
#pragma once

#include <cuda_runtime.h>

#include <type_traits>

#include "traversal/device/bvh2_traverse.h"

namespace bvhlab::trav {

namespace ww_detail {

/// The exact form: slab_entry, shared with the CPU.
struct ExactSlabs {
    Vec3 o, inv;
    ExactSlabs() = default;
    __device__ __forceinline__ ExactSlabs(Vec3 org, Vec3 inv_dir) : o(org), inv(inv_dir) {}
    /// Whether the box is entered within [tmin, tmax]; its entry distance in `tn`.
    __device__ __forceinline__ bool entry(float lox, float hix, float loy, float hiy, float loz, float hiz, float tmin,
                                          float tmax, float& tn) const {
        tn = slab_entry(lox, hix, loy, hiy, loz, hiz, o, inv, tmin, tmax);
        return tn != INFINITY;
    }
};

/// The FMA form: one FMA per slab distance, plane * inv - o * inv with o * inv computed once
/// per ray, and the near and far plane of each axis picked by the direction's sign (one
/// select each) instead of a min and a max of both. About 20 instructions per child box
/// against slab_entry's 27.
/// Robustness: fma(plane, inv, -ood) differs from the exact (plane - o) * inv by the rounding
/// of ood = o * inv (at most 2^-24 |ood|, and as much again for rounding ood +- s) and its own
/// relative rounding. So each axis's near distance is lowered by s = 2^-22 |ood| (twice the
/// bound) and its far distance raised by the same, and the far distances carry slab_entry's
/// relative widening (folded into a widened reciprocal and offset, so it costs nothing per box). The slack is per axis:
/// on an axis nearly parallel to the ray |ood| is huge, but so is every distance on that axis, and the slack moves only
/// planes within 2^-22 |o| of the origin. (A first version added the largest axis's slack to the exit distance in t
/// units; on furball's diffuse rays it cost 25%: one such lane per warp made the whole warp enter extra boxes.)
struct FmaSlabs {
    Vec3 inv, inv_far;         // reciprocal direction; widened by (1 + 2^-21) for far planes
    Vec3 ood_near, ood_far;    // o * inv plus / minus the slack (widened for far planes)
    bool neg_x, neg_y, neg_z;  // direction negative: the near plane is hi
    FmaSlabs() = default;
    __device__ __forceinline__ FmaSlabs(Vec3 org, Vec3 inv_dir) : inv(inv_dir) {
        constexpr float kWiden = 1.0000005f;  // 1 + 2^-21: the far side's relative rounding
        auto axis = [&](float o, float iv, float& near_off, float& far_off, float& iv_far) {
            const float ood = o * iv;
            const float slack = fabsf(ood) * 2.3841858e-7f;  // 2^-22
            near_off = ood + slack;
            far_off = (ood - slack) * kWiden;
            iv_far = iv * kWiden;
        };
        axis(org.x, inv.x, ood_near.x, ood_far.x, inv_far.x);
        axis(org.y, inv.y, ood_near.y, ood_far.y, inv_far.y);
        axis(org.z, inv.z, ood_near.z, ood_far.z, inv_far.z);
        neg_x = inv.x < 0.0f;
        neg_y = inv.y < 0.0f;
        neg_z = inv.z < 0.0f;
    }
    /// Whether the box is entered within [tmin, tmax]; its entry distance in `tn`. (Returning
    /// +inf for a miss, as slab_entry does, cost 4 more compares and selects per node.)
    __device__ __forceinline__ bool entry(float lox, float hix, float loy, float hiy, float loz, float hiz, float tmin,
                                          float tmax, float& tn) const {
        const float nx = fmaf(neg_x ? hix : lox, inv.x, -ood_near.x);
        const float ny = fmaf(neg_y ? hiy : loy, inv.y, -ood_near.y);
        const float nz = fmaf(neg_z ? hiz : loz, inv.z, -ood_near.z);
        const float fx = fmaf(neg_x ? lox : hix, inv_far.x, -ood_far.x);
        const float fy = fmaf(neg_y ? loy : hiy, inv_far.y, -ood_far.y);
        const float fz = fmaf(neg_z ? loz : hiz, inv_far.z, -ood_far.z);
        tn = max_f(max_f(nx, ny), max_f(nz, tmin));
        return tn <= min_f(min_f(fx, fy), min_f(fz, tmax));
    }
};

/// The traversal stack in local memory (the compiler's stack frame, cached in L1).
struct LocalStack {
    int32_t s[kBvh2StackSize + 1];
    __device__ __forceinline__ int32_t& operator[](int i) { return s[i]; }
};

/// The traversal stack in shared memory: kBvh2StackSize + 1 words per thread, entry i of
/// thread t at [i * blockDim.x + t] so that a warp's pushes hit 32 different banks. Needs
/// (kBvh2StackSize + 1) * 4 bytes of dynamic shared memory per thread.
struct SharedStack {
    int32_t* base;
    uint32_t stride;
    __device__ __forceinline__ SharedStack() {
        extern __shared__ int32_t bvhlab_stack_smem[];
        base = bvhlab_stack_smem + threadIdx.x;
        stride = blockDim.x;
    }
    __device__ __forceinline__ int32_t& operator[](int i) { return base[uint32_t(i) * stride]; }
};

/// Dynamic shared memory per thread of a kernel whose stack is a SharedStack.
constexpr uint32_t kSharedStackBytes = (kBvh2StackSize + 1) * sizeof(int32_t);

/// One node of the while-while node loop: the node's two boxes tested, the near child hit next
/// (child 0 on equal entry distances, as traverse_bvh2), the far one pushed when both are hit,
/// or the top of the stack when neither is. Shared by while_while_step and the two-level step.
template <class Slabs, class Stack>
__device__ __forceinline__ void visit_node(const accel::Bvh2Node* nodes, const Slabs& slabs, float tmin, float t_hit,
                                           Stack& stack, int& sp, int32_t& node) {
    // One 64-bit address and immediate offsets (4 * node + 1 in int arithmetic had cost an
    // address computation per load).
    const float4* p = reinterpret_cast<const float4*>(nodes + node);
    const float4 c0 = __ldg(p + 0);  // child 0: lo.x hi.x lo.y hi.y
    const float4 c1 = __ldg(p + 1);  // child 1: lo.x hi.x lo.y hi.y
    const float4 zz = __ldg(p + 2);  // lo.z hi.z of child 0, then child 1
    const int2 ch = __ldg(reinterpret_cast<const int2*>(p + 3));
    float t0, t1;
    const bool hit0 = slabs.entry(c0.x, c0.y, c0.z, c0.w, zz.x, zz.y, tmin, t_hit, t0);
    const bool hit1 = slabs.entry(c1.x, c1.y, c1.z, c1.w, zz.z, zz.w, tmin, t_hit, t1);
    if (!hit0 && !hit1) {
        node = stack[sp--];
    } else {
        const bool first0 = hit0 && (!hit1 || t0 <= t1);
        node = first0 ? ch.x : ch.y;
        if (hit0 && hit1) stack[++sp] = first0 ? ch.y : ch.x;
    }
}

}  // namespace ww_detail

/// The traversal stack of the while-while family: local memory, or shared memory.
template <bool kSharedStack>
using WhileWhileStack = std::conditional_t<kSharedStack, ww_detail::SharedStack, ww_detail::LocalStack>;

/// The bottom of the stack and the end of a ray. Above every node index, below every leaf
/// reference as unsigned: the loop conditions are one unsigned compare each.
constexpr int32_t kWhileWhileSentinel = 0x76543210;

/// One step of Aila & Laine's while-while traversal: the node loop until this lane (or,
/// speculative, every lane) has a leaf, then the leaf loop. The ray is done when `node` is
/// kWhileWhileSentinel. A kernel may hand a finished lane a new ray between steps (dynamic
/// fetch) while the others go on. The ray's state comes in as plain values and the stack
/// beside them: a struct that held the stack array had nvcc keep every field in local memory
/// (stack frame 264 -> 368 bytes). Stack: kBvh2StackSize entries plus the sentinel at the
/// bottom, so popping needs no emptiness test. The build-time choices, each measured in
/// experiments/NOTES.md:
/// - kSpeculative: postponed leaf tests (section 4 of the paper). A lane that has found a
///   leaf keeps traversing until every active lane of its warp has one, then the warp tests
///   leaves together, so the leaf loop runs with more lanes busy.
/// - Slabs = FmaSlabs: slab distances as one FMA each, lo * inv - o * inv with o * inv computed
///   once per ray, instead of (lo - o) * inv (ExactSlabs); see FmaSlabs for why no box is lost.
/// - Stack = SharedStack: the stack in shared memory instead of local memory.
template <bool kAnyHit, bool kSpeculative, class Slabs, class Stack>
__device__ __forceinline__ void while_while_step(const Bvh2View& v, Vec3 o, Vec3 d, const Slabs& slabs, float tmin,
                                                 float& t_hit, float& u_hit, float& v_hit, int32_t& k_hit, Stack& stack,
                                                 int& sp, int32_t& node, int32_t& leaf) {
    while (uint32_t(node) < uint32_t(kWhileWhileSentinel)) {
        ww_detail::visit_node(v.nodes, slabs, tmin, t_hit, stack, sp, node);
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
    // The postponed leaf, then any leaves popped right behind it.
    while (leaf < 0) {
        const uint32_t first = accel::Bvh2Node::leaf_first(leaf);
        const uint32_t end = first + accel::Bvh2Node::leaf_count(leaf);
        for (uint32_t k = first; k < end; ++k) {
            const float4* tri = reinterpret_cast<const float4*>(v.tris + k);
            const float4 r0 = __ldg(tri), r1 = __ldg(tri + 1), r2 = __ldg(tri + 2);
            float t, u, w;
            if (accel::WoopTriangle::intersect_rows(&r0.x, &r1.x, &r2.x, o, d, tmin, t_hit, t, u, w)) {
                t_hit = t;
                u_hit = u;
                v_hit = w;
                k_hit = int32_t(k);
                if constexpr (kAnyHit) {  // any hit ends the ray
                    node = kWhileWhileSentinel;
                    leaf = 0;
                    return;
                }
            }
        }
        leaf = node;
        if (node < 0) node = stack[sp--];
    }
}

/// The while-while family as a per-ray functor (launch_per_ray, launch_persistent), and as a
/// resumable one (State, Stack, start, step, done, result) for launch_dynamic_fetch.
template <bool kAnyHit, bool kSpeculative, bool kFmaSlabs, bool kSharedStack = false>
struct WhileWhileTrace {
    using Slabs = std::conditional_t<kFmaSlabs, ww_detail::FmaSlabs, ww_detail::ExactSlabs>;
    using Stack = WhileWhileStack<kSharedStack>;
    /// A ray in flight, for dynamic fetch.
    struct State {
        Vec3 o, d;
        Slabs slabs;
        float tmin, t_hit, u_hit, v_hit;
        int32_t k_hit, node, leaf;
        int sp;
    };
    Bvh2View view;

    __device__ __forceinline__ Hit operator()(const Ray& r) const {
        const Slabs slabs(r.org, safe_reciprocal(r.dir));
        float t_hit = r.tmax, u_hit = 0.0f, v_hit = 0.0f;
        int32_t k_hit = -1, node = 0, leaf = 0;  // node 0: the root; leaf 0: none postponed
        Stack stack;
        stack[0] = kWhileWhileSentinel;
        int sp = 0;
        while (node != kWhileWhileSentinel)
            while_while_step<kAnyHit, kSpeculative>(view, r.org, r.dir, slabs, r.tmin, t_hit, u_hit, v_hit, k_hit,
                                                    stack, sp, node, leaf);
        return hit(k_hit, t_hit, u_hit, v_hit);
    }

    __device__ __forceinline__ void start(State& s, Stack& stack, const Ray& r) const {
        s = {r.org, r.dir, Slabs(r.org, safe_reciprocal(r.dir)), r.tmin, r.tmax, 0.0f, 0.0f, -1, 0, 0, 0};
        stack[0] = kWhileWhileSentinel;
    }
    __device__ __forceinline__ void step(State& s, Stack& stack) const {
        while_while_step<kAnyHit, kSpeculative>(view, s.o, s.d, s.slabs, s.tmin, s.t_hit, s.u_hit, s.v_hit, s.k_hit,
                                                stack, s.sp, s.node, s.leaf);
    }
    __device__ __forceinline__ bool done(const State& s) const { return s.node == kWhileWhileSentinel; }
    __device__ __forceinline__ Hit result(const State& s) const { return hit(s.k_hit, s.t_hit, s.u_hit, s.v_hit); }

private:
    __device__ __forceinline__ Hit hit(int32_t k, float t, float u, float w) const {
        if (k < 0) return Hit::miss();
        return {int32_t(__ldg(view.tri_ids + k)), t, u, w};
    }
};

}  // namespace bvhlab::trav
