// SPDX-License-Identifier: MIT
// Aila & Laine's while-while traversal (bvh2_while_while.cuh) over a two-level BVH: the TLAS and
// every instance's BLAS are walked by the same node loop, on one stack, as traverse_two_level
// walks them. Device only.
#pragma once

#include <cuda_runtime.h>

#include <type_traits>

#include "traversal/device/bvh2_while_while.cuh"
#include "traversal/device/two_level_traverse.h"

namespace bvhlab::trav {

/// Marks the bottom of an instance's entries on the two-level stack: popped, the ray leaves the
/// instance. Above every node index and kWhileWhileSentinel as unsigned, so the node loop's one
/// compare stops at it, and positive, so the leaf loop never takes it for a leaf.
constexpr int32_t kLeaveInstance = kWhileWhileSentinel + 1;

/// The two-level stack: the TLAS's entries, the mark, the BLAS's, and the sentinel.
struct TwoLevelStack {
    int32_t s[2 * kBvh2StackSize + 2];
    __device__ __forceinline__ int32_t& operator[](int i) { return s[i]; }
};

/// A ray in flight through a two-level BVH. `o`, `d` and `slabs` are the ray in the space of
/// the level it is in (the world in the TLAS, the instance's space in a BLAS); `cur` is the
/// BLAS it is in, or the TLAS (with null triangles).
template <class Slabs>
struct TwoLevelRay {
    Vec3 wo, wd;  // the ray in the world
    Vec3 o, d;
    Slabs slabs;
    Bvh2View cur;
    float tmin, t_hit, u_hit, v_hit;
    int32_t id_hit;  // scene-wide id, or -1
    uint32_t first_id;
    int32_t node, leaf;
    int sp;
};

/// One step of the two-level while-while traversal; the ray is done when `r.node` is
/// kWhileWhileSentinel. As while_while_step, with the instance's changes of space: a TLAS leaf
/// (one instance) that the node loop reaches is entered at once (the mark pushed, the ray moved
/// into the instance's space, the BLAS's root next), and the mark, popped, moves the ray back.
/// Only BLAS leaves are postponed; a lane leaves its instance inside the node loop unless it
/// still holds a postponed leaf, which needs the instance's space: then after the leaf loop.
template <bool kAnyHit, bool kSpeculative, class Slabs>
__device__ __forceinline__ void two_level_step(const TwoLevelView& v, TwoLevelRay<Slabs>& r, TwoLevelStack& stack) {
    auto leave = [&] {
        r.o = r.wo;
        r.d = r.wd;
        r.slabs = Slabs(r.wo, safe_reciprocal(r.wd));
        r.cur = {v.tlas, nullptr, nullptr};
        r.node = stack[r.sp--];
    };
    while (true) {
        if (r.node < 0 && r.cur.tris == nullptr) {  // a TLAS leaf: enter its instance
            const accel::InstanceRecord* inst = v.instances + __ldg(v.tlas_ids + accel::Bvh2Node::leaf_first(r.node));
            const float4* m = reinterpret_cast<const float4*>(inst->world_to_object);
            const float4 m0 = __ldg(m), m1 = __ldg(m + 1), m2 = __ldg(m + 2);
            const uint2 bf = __ldg(reinterpret_cast<const uint2*>(m + 3));  // blas, first_id
            r.o = {m0.x * r.wo.x + m0.y * r.wo.y + m0.z * r.wo.z + m0.w,
                   m1.x * r.wo.x + m1.y * r.wo.y + m1.z * r.wo.z + m1.w,
                   m2.x * r.wo.x + m2.y * r.wo.y + m2.z * r.wo.z + m2.w};
            r.d = {m0.x * r.wd.x + m0.y * r.wd.y + m0.z * r.wd.z, m1.x * r.wd.x + m1.y * r.wd.y + m1.z * r.wd.z,
                   m2.x * r.wd.x + m2.y * r.wd.y + m2.z * r.wd.z};
            r.slabs = Slabs(r.o, safe_reciprocal(r.d));
            const Bvh2View* b = v.blas + bf.x;
            r.cur = {
                reinterpret_cast<const accel::Bvh2Node*>(__ldg(reinterpret_cast<const unsigned long long*>(&b->nodes))),
                reinterpret_cast<const accel::WoopTriangle*>(
                    __ldg(reinterpret_cast<const unsigned long long*>(&b->tris))),
                reinterpret_cast<const uint32_t*>(__ldg(reinterpret_cast<const unsigned long long*>(&b->tri_ids)))};
            r.first_id = bf.y;
            stack[++r.sp] = kLeaveInstance;
            r.node = 0;
        }
        if (uint32_t(r.node) >= uint32_t(kWhileWhileSentinel)) break;  // done, or a postponed leaf holds the mark
        ww_detail::visit_node(r.cur.nodes, r.slabs, r.tmin, r.t_hit, stack, r.sp, r.node);
        if (r.cur.tris != nullptr) {
            if (r.node < 0 && r.leaf >= 0) {  // postpone the first leaf found
                r.leaf = r.node;
                r.node = stack[r.sp--];
            }
            if (r.node == kLeaveInstance && r.leaf >= 0) leave();
        }
        if constexpr (kSpeculative) {
            if (!__any_sync(__activemask(), r.leaf >= 0)) break;
        } else {
            if (r.leaf < 0) break;
        }
    }
    while (r.leaf < 0) {
        const uint32_t first = accel::Bvh2Node::leaf_first(r.leaf);
        const uint32_t end = first + accel::Bvh2Node::leaf_count(r.leaf);
        for (uint32_t k = first; k < end; ++k) {
            const float4* tri = reinterpret_cast<const float4*>(r.cur.tris + k);
            const float4 r0 = __ldg(tri), r1 = __ldg(tri + 1), r2 = __ldg(tri + 2);
            float t, u, w;
            if (accel::WoopTriangle::intersect_rows(&r0.x, &r1.x, &r2.x, r.o, r.d, r.tmin, r.t_hit, t, u, w)) {
                r.t_hit = t;
                r.u_hit = u;
                r.v_hit = w;
                r.id_hit = int32_t(r.first_id + __ldg(r.cur.tri_ids + k));
                if constexpr (kAnyHit) {
                    r.node = kWhileWhileSentinel;
                    r.leaf = 0;
                    return;
                }
            }
        }
        r.leaf = r.node;
        if (r.node < 0) r.node = stack[r.sp--];
    }
    if (r.node == kLeaveInstance) leave();
}

/// The two-level while-while traversal as a per-ray functor and as a resumable one for
/// launch_dynamic_fetch.
template <bool kAnyHit, bool kSpeculative, bool kFmaSlabs>
struct TwoLevelWhileWhileTrace {
    using Slabs = std::conditional_t<kFmaSlabs, ww_detail::FmaSlabs, ww_detail::ExactSlabs>;
    using State = TwoLevelRay<Slabs>;
    using Stack = TwoLevelStack;
    TwoLevelView view;

    __device__ __forceinline__ void start(State& s, Stack& stack, const Ray& r) const {
        const Slabs slabs(r.org, safe_reciprocal(r.dir));
        s = {r.org, r.dir, r.org, r.dir, slabs, {view.tlas, nullptr, nullptr}, r.tmin, r.tmax, 0.0f, 0.0f,
             -1,    0,     0,     0,     0};
        stack[0] = kWhileWhileSentinel;
    }
    __device__ __forceinline__ void step(State& s, Stack& stack) const {
        two_level_step<kAnyHit, kSpeculative>(view, s, stack);
    }
    __device__ __forceinline__ bool done(const State& s) const { return s.node == kWhileWhileSentinel; }
    __device__ __forceinline__ Hit result(const State& s) const {
        return s.id_hit < 0 ? Hit::miss() : Hit{s.id_hit, s.t_hit, s.u_hit, s.v_hit};
    }
    __device__ __forceinline__ Hit operator()(const Ray& r) const {
        State s;
        Stack stack;
        start(s, stack, r);
        while (!done(s)) step(s, stack);
        return result(s);
    }
};

}  // namespace bvhlab::trav
