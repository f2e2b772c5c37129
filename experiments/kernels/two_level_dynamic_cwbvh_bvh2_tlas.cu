// SPDX-License-Identifier: MIT
// Kernel 'two-level-dynamic-cwbvh-bvh2-tlas' (a measured alternative that lost, experiments/NOTES.md):
// the two-level-cwbvh layout walked with its BVH2 TLAS (two slab tests per TLAS node) and the
// CWBVH BLAS, a step being one node of either level, in the dynamic-fetch wrapper. Lanes in the
// TLAS and lanes in a BLAS run different code in the same step; the default kernel
// (two-level-dynamic-cwbvh) walks the 8-wide TLAS with the same node code as the BLAS.
#include "traversal/device/two_level_cwbvh_traverse.h"
#include "traversal/kernels/launch_helpers.cuh"

namespace bvhlab::trav {
namespace {

/// The TLAS's stack and the current BLAS's node-group stack.
struct Bvh2TlasStack {
    CwbvhStack cw;
    int32_t tlas[kBvh2StackSize];
};

/// A ray in flight through a two-level BVH with CWBVH BLAS: what a dynamic-fetch kernel keeps
/// between steps. `cw` is the ray in the space of the level it is in (the world in the TLAS) with
/// the closest t so far; `wo`, `wd` the ray in the world.
struct Bvh2TlasState {
    CwbvhState cw;
    Vec3 wo, wd;
    CwbvhView cur;      // the BLAS the ray is in
    uint32_t first_id;  // its instance's first scene-wide id
    int32_t id_hit;     // scene-wide id of the closest hit, or -1
    int32_t node;       // the next TLAS node (>= 0) while in the TLAS
    int tlas_sp;
    bool in_blas, done;
};

namespace bvh2_tlas_detail {

/// A TLAS node: four 16-byte read-only loads on the device.
BVHLAB_HD BVHLAB_FORCEINLINE accel::Bvh2Node load_tlas_node(const accel::Bvh2Node* p) {
#if defined(__CUDA_ARCH__)
    accel::Bvh2Node n;
    const float4* q = reinterpret_cast<const float4*>(p);
    float4* out = reinterpret_cast<float4*>(&n);
    BVHLAB_UNROLL
    for (int i = 0; i < 4; ++i) out[i] = __ldg(q + i);
    return n;
#else
    return *p;
#endif
}
static_assert(sizeof(accel::Bvh2Node) == 64 && alignof(accel::Bvh2Node) >= 16, "four 16-byte loads");

/// Moves the ray into the instance of TLAS leaf `leaf` and starts its BLAS at the root.
BVHLAB_HD BVHLAB_FORCEINLINE void enter(const TwoLevelView& v, Bvh2TlasState& s, int32_t leaf) {
    const accel::InstanceRecord& inst = v.instances[v.tlas_ids[accel::Bvh2Node::leaf_first(leaf)]];
    cw_detail::set_ray(s.cw, inst.point(s.wo), inst.vector(s.wd));
    s.cur = v.cw_blas[inst.blas];
    s.first_id = inst.first_id;
    s.cw.group_base = 0;
    s.cw.group_bits = (1u << (accel::CwbvhNode::kInteriorBit + s.cw.axes.octant)) | 1u;
    s.cw.sp = 0;
    s.in_blas = true;
}

/// The TLAS entry on top of the stack: a node to visit next, or an instance (a TLAS leaf) to
/// enter; the end of the ray when the stack is empty.
BVHLAB_HD BVHLAB_FORCEINLINE void pop_tlas(const TwoLevelView& v, Bvh2TlasState& s, const Bvh2TlasStack& stack,
                                           TraversalCounters* counters) {
    if (s.tlas_sp == 0) {
        s.done = true;
        return;
    }
    const int32_t ref = stack.tlas[--s.tlas_sp];
    if (ref >= 0) {
        s.node = ref;
        return;
    }
    if (counters) ++counters->leaves;
    enter(v, s, ref);
}

}  // namespace bvh2_tlas_detail

/// Starts `ray` at the TLAS root.
BVHLAB_HD BVHLAB_FORCEINLINE void bvh2_tlas_start(Bvh2TlasState& s, const Ray& ray) {
    cw_detail::set_ray(s.cw, ray.org, ray.dir);
    s.cw.tmin = ray.tmin;
    s.cw.t_hit = ray.tmax;
    s.cw.u_hit = s.cw.v_hit = 0.0f;
    s.cw.k_hit = -1;
    s.cw.group_base = s.cw.group_bits = 0;
    s.cw.sp = 0;
    s.wo = ray.org;
    s.wd = ray.dir;
    s.cur = {nullptr, nullptr, nullptr, nullptr};
    s.first_id = 0;
    s.id_hit = -1;
    s.node = 0;
    s.tlas_sp = 0;
    s.in_blas = s.done = false;
}

/// One step: one TLAS node, or one node of the current instance's BLAS (cwbvh_step) and its
/// triangles. A TLAS leaf taken moves the ray into its instance; the BLAS finished, the ray
/// returns to the world and the TLAS stack. Counters add up both levels (an instance entered
/// counts as a leaf).
template <bool kAnyHit, bool kVertexTris = false>
BVHLAB_HD BVHLAB_FORCEINLINE void bvh2_tlas_step(const TwoLevelView& v, Bvh2TlasState& s, Bvh2TlasStack& stack,
                                                 TraversalCounters* counters) {
    if (s.in_blas) {
        cwbvh_step<kAnyHit, kVertexTris>(s.cur, s.cw, stack.cw, counters);
        if (s.cw.k_hit >= 0) {
            s.id_hit = int32_t(s.first_id + s.cur.tri_ids[s.cw.k_hit]);
            s.cw.k_hit = -1;
            if (kAnyHit) {
                s.done = true;
                return;
            }
        }
        if (!cwbvh_done(s.cw)) return;
        s.in_blas = false;  // back to the world
        cw_detail::set_ray(s.cw, s.wo, s.wd);
        bvh2_tlas_detail::pop_tlas(v, s, stack, counters);
        return;
    }
    const accel::Bvh2Node n = bvh2_tlas_detail::load_tlas_node(v.tlas + s.node);
    if (counters) ++counters->nodes;
    const Vec3 o = s.cw.axes.o, inv{s.cw.axes.inv[0], s.cw.axes.inv[1], s.cw.axes.inv[2]};
    const float t0 =
        slab_entry(n.c0_lo_x, n.c0_hi_x, n.c0_lo_y, n.c0_hi_y, n.c0_lo_z, n.c0_hi_z, o, inv, s.cw.tmin, s.cw.t_hit);
    const float t1 =
        slab_entry(n.c1_lo_x, n.c1_hi_x, n.c1_lo_y, n.c1_hi_y, n.c1_lo_z, n.c1_hi_z, o, inv, s.cw.tmin, s.cw.t_hit);
    const bool hit0 = t0 != INFINITY, hit1 = t1 != INFINITY;
    if (!hit0 && !hit1) {
        bvh2_tlas_detail::pop_tlas(v, s, stack, counters);
        return;
    }
    const bool first0 = hit0 && (!hit1 || t0 <= t1);
    const int32_t next = first0 ? n.child[0] : n.child[1];
    if (hit0 && hit1) stack.tlas[s.tlas_sp++] = first0 ? n.child[1] : n.child[0];
    if (next >= 0) {
        s.node = next;
        return;
    }
    if (counters) ++counters->leaves;
    bvh2_tlas_detail::enter(v, s, next);
}

/// Whether the ray has finished.
BVHLAB_HD BVHLAB_FORCEINLINE bool bvh2_tlas_done(const Bvh2TlasState& s) { return s.done; }

/// The hit of a finished ray (scene-wide ids, TwoLevelBvh).
BVHLAB_HD BVHLAB_FORCEINLINE Hit bvh2_tlas_result(const Bvh2TlasState& s) {
    return s.id_hit < 0 ? Hit::miss() : Hit{s.id_hit, s.cw.t_hit, s.cw.u_hit, s.cw.v_hit};
}

template <bool kAnyHit, bool kVertexTris>
struct Bvh2TlasTrace {
    using State = Bvh2TlasState;
    using Stack = Bvh2TlasStack;
    TwoLevelView view;
    __device__ __forceinline__ void start(State& s, Stack&, const Ray& r) const { bvh2_tlas_start(s, r); }
    __device__ __forceinline__ void step(State& s, Stack& stack) const {
        bvh2_tlas_step<kAnyHit, kVertexTris>(view, s, stack, nullptr);
    }
    __device__ __forceinline__ bool done(const State& s) const { return bvh2_tlas_done(s); }
    __device__ __forceinline__ Hit result(const State& s) const { return bvh2_tlas_result(s); }
};

void launch(const LaunchArgs& a) {
    for_query(a, [&](auto any) {
        const uint32_t threshold = a.fetch_threshold ? a.fetch_threshold : kDefaultFetchThreshold;
        if (a.two_level.cw_vertices)
            launch_dynamic_fetch(a, 128, Bvh2TlasTrace<decltype(any)::value, true>{a.two_level}, threshold);
        else
            launch_dynamic_fetch(a, 128, Bvh2TlasTrace<decltype(any)::value, false>{a.two_level}, threshold);
    });
}

}  // namespace

BVHLAB_REGISTER_KERNEL({"two-level-dynamic-cwbvh-bvh2-tlas", Layout::kTwoLevelCwbvh,
                        "two-level-cwbvh with its BVH2 TLAS: a step is one BVH2 TLAS node or one CWBVH BLAS node "
                        "(dynamic fetch); slower than two-level-dynamic-cwbvh",
                        uint32_t(kBvh2StackSize), false, 128, launch, 1024, true});

}  // namespace bvhlab::trav
