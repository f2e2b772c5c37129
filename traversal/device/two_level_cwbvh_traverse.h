// SPDX-License-Identifier: MIT
// Two-level traversal of the two-level-cwbvh layout (accel::TwoLevelBvh with cw_tlas and
// cw_blas), written once for host and device: the CPU tracer and the GPU kernel
// 'two-level-dynamic-cwbvh' run this code. Both levels are compressed 8-wide BVHs, so a step is
// the same node fetch and eight-box test whichever level a lane is in (cwbvh_traverse.h);
// only what follows differs: a BLAS step tests the triangles of the leaves it entered, a TLAS
// step enters the first instance of the leaves it entered. One stack holds both levels: node
// groups, the instances of a TLAS node still to enter (instance groups), and under each
// instance's entries a mark that, popped, moves the ray back to the world.
#pragma once

#include "traversal/device/cwbvh_traverse.h"
#include "traversal/device/two_level_traverse.h"

namespace bvhlab::trav {

/// Entries of the shared stack: per TLAS level a node group and an instance group, the mark,
/// per BLAS level a node group.
constexpr int kTwoLevelCwbvhStackSize = 3 * kCwbvhStackSize + 1;

struct TwoLevelCwbvhStack {
    uint32_t base[kTwoLevelCwbvhStackSize];
    uint32_t bits[kTwoLevelCwbvhStackSize];  ///< a node group (bits 24..31 set), an instance group (bits 0..23), or 0:
                                             ///< the mark
};

/// A ray in flight: what a dynamic-fetch kernel keeps between steps. `cw` is the ray in the
/// space of the level it is in (the world in the TLAS), its node group and closest t; `wo`,
/// `wd` the ray in the world.
struct TwoLevelCwbvhState {
    CwbvhState cw;
    Vec3 wo, wd;
    const accel::CwbvhNode* nodes;  // the level's nodes: the TLAS's, or the instance's BLAS's
    uint32_t blas, first_id;        // the instance's BLAS and its first scene-wide id
    int32_t id_hit;                 // scene-wide id of the closest hit, or -1
    bool in_blas, done;
};

namespace tlc_detail {

/// The root of the level whose nodes are `nodes`: the one interior child (slot 0) of a virtual
/// parent whose children start at node 0, as cwbvh_start.
BVHLAB_HD BVHLAB_FORCEINLINE void start_level(TwoLevelCwbvhState& s, const accel::CwbvhNode* nodes) {
    s.nodes = nodes;
    s.cw.group_base = 0;
    s.cw.group_bits = (1u << (accel::CwbvhNode::kInteriorBit + s.cw.axes.octant)) | 1u;
}

BVHLAB_HD BVHLAB_FORCEINLINE void push(TwoLevelCwbvhState& s, TwoLevelCwbvhStack& st, uint32_t base, uint32_t bits) {
    st.base[s.cw.sp] = base;
    st.bits[s.cw.sp++] = bits;
}

/// Enters the first instance of an instance group (TLAS leaf slots from `base`): the rest of
/// the group and the mark wait on the stack, the ray moves into the instance's space and starts
/// its BLAS at the root.
BVHLAB_HD BVHLAB_FORCEINLINE void enter(const TwoLevelView& v, TwoLevelCwbvhState& s, TwoLevelCwbvhStack& st,
                                        uint32_t base, uint32_t bits) {
    const uint32_t k = base + lowest_bit(bits);
    bits &= bits - 1u;
    if (bits) push(s, st, base, bits);
    push(s, st, 0u, 0u);
    const accel::InstanceRecord& inst = v.instances[v.cw_tlas_ids[k]];
    cw_detail::set_ray(s.cw, inst.point(s.wo), inst.vector(s.wd));
    s.blas = inst.blas;
    s.first_id = inst.first_id;
    s.in_blas = true;
    start_level(s, v.cw_blas[inst.blas].nodes);
}

/// Pops until the ray has a node group to visit: a mark moves it back to the world, an
/// instance group enters its next instance; the ray is done when the stack is empty.
BVHLAB_HD BVHLAB_FORCEINLINE void settle(const TwoLevelView& v, TwoLevelCwbvhState& s, TwoLevelCwbvhStack& st) {
    while (!(s.cw.group_bits & 0xFF000000u)) {
        if (s.cw.sp == 0) {
            s.done = true;
            return;
        }
        --s.cw.sp;
        const uint32_t base = st.base[s.cw.sp], bits = st.bits[s.cw.sp];
        if (bits == 0) {  // the mark: back to the world
            s.in_blas = false;
            s.nodes = v.cw_tlas;
            cw_detail::set_ray(s.cw, s.wo, s.wd);
        } else if (bits & 0xFF000000u) {
            s.cw.group_base = base;
            s.cw.group_bits = bits;
        } else {
            enter(v, s, st, base, bits);
        }
    }
}

}  // namespace tlc_detail

/// Starts `ray` at the TLAS root.
BVHLAB_HD BVHLAB_FORCEINLINE void two_level_cwbvh_start(const TwoLevelView& v, TwoLevelCwbvhState& s, const Ray& ray) {
    cw_detail::set_ray(s.cw, ray.org, ray.dir);
    s.cw.tmin = ray.tmin;
    s.cw.t_hit = ray.tmax;
    s.cw.u_hit = s.cw.v_hit = 0.0f;
    s.cw.k_hit = -1;
    s.cw.sp = 0;
    s.wo = ray.org;
    s.wd = ray.dir;
    s.blas = s.first_id = 0;
    s.id_hit = -1;
    s.in_blas = s.done = false;
    tlc_detail::start_level(s, v.cw_tlas);
}

/// One step: the nearest interior child left in the node group, of the TLAS or of the current
/// BLAS, is fetched and its eight boxes tested (as cwbvh_step); what is left of the group waits
/// on the stack. In a BLAS the triangles of the leaves entered are tested; in the TLAS the
/// first instance of the leaves entered is entered (the children entered wait under it).
/// Counters add up both levels.
template <bool kAnyHit, bool kVertexTris = false>
BVHLAB_HD BVHLAB_FORCEINLINE void two_level_cwbvh_step(const TwoLevelView& v, TwoLevelCwbvhState& s,
                                                       TwoLevelCwbvhStack& st, TraversalCounters* counters) {
    CwbvhState& c = s.cw;
    uint32_t w[20];
    const uint32_t hits = cw_detail::visit_nearest(
        s.nodes, v.cw_one, c, w, counters, [&](uint32_t base, uint32_t bits) { tlc_detail::push(s, st, base, bits); });
    const uint32_t leaf_base = w[cw_detail::kWordTriBase];
    const uint32_t leaf_bits = hits & 0x00FFFFFFu;
    if (s.in_blas) {
        const CwbvhView& b = v.cw_blas[s.blas];
        const int32_t k = cw_detail::test_triangles<kAnyHit, kVertexTris>(b, leaf_base, leaf_bits, c, counters);
        if (k >= 0) {
            s.id_hit = int32_t(s.first_id + b.tri_ids[k]);
            if (kAnyHit) {  // any hit ends the ray
                s.done = true;
                return;
            }
        }
    } else if (leaf_bits) {
        if (c.group_bits & 0xFF000000u) tlc_detail::push(s, st, c.group_base, c.group_bits);
        tlc_detail::enter(v, s, st, leaf_base, leaf_bits);
        return;
    }
    tlc_detail::settle(v, s, st);
}

/// Whether the ray has finished.
BVHLAB_HD BVHLAB_FORCEINLINE bool two_level_cwbvh_done(const TwoLevelCwbvhState& s) { return s.done; }

/// The hit of a finished ray (scene-wide ids, TwoLevelBvh).
BVHLAB_HD BVHLAB_FORCEINLINE Hit two_level_cwbvh_result(const TwoLevelCwbvhState& s) {
    return s.id_hit < 0 ? Hit::miss() : Hit{s.id_hit, s.cw.t_hit, s.cw.u_hit, s.cw.v_hit};
}

/// Closest or any hit of `ray` through a two-level-cwbvh layout.
template <bool kAnyHit, bool kVertexTris = false>
BVHLAB_HD inline Hit traverse_two_level_cwbvh(const TwoLevelView& v, const Ray& ray,
                                              TraversalCounters* counters = nullptr) {
    TwoLevelCwbvhState s;
    TwoLevelCwbvhStack stack;
    two_level_cwbvh_start(v, s, ray);
    while (!two_level_cwbvh_done(s)) two_level_cwbvh_step<kAnyHit, kVertexTris>(v, s, stack, counters);
    return two_level_cwbvh_result(s);
}

}  // namespace bvhlab::trav
