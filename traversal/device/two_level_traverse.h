// SPDX-License-Identifier: MIT
// Two-level traversal (accel/layouts/two_level.h), written once for host and device: at an
// instance the ray is moved into the instance's space (origin and direction through the inverse
// transform, so t keeps its meaning) and walks the mesh's BLAS with the current closest t.
#pragma once

#include "accel/layouts/two_level.h"
#include "traversal/device/bvh2_traverse.h"
#include "traversal/device/cwbvh_traverse.h"

namespace bvhlab::trav {

/// A two-level BVH as traversal sees it: plain pointers, host or device memory.
struct TwoLevelView {
    const accel::Bvh2Node* tlas;
    const uint32_t* tlas_ids;  ///< instance index of each TLAS leaf entry
    const accel::InstanceRecord* instances;
    const Bvh2View* blas;                       ///< one view per BLAS (BVH2 BLAS), else null
    const CwbvhView* cw_blas = nullptr;         ///< one view per BLAS (CWBVH BLAS), else null
    bool cw_vertices = false;                   ///< the CWBVH BLAS hold vertex triangles (CwTris::kVertices)
    const accel::CwbvhNode* cw_tlas = nullptr;  ///< the 8-wide TLAS (two-level-cwbvh), else null
    const uint32_t* cw_tlas_ids = nullptr;      ///< instance index of each of its leaf entries
    uint32_t cw_one = accel::kCwbvhUnpackOne;   ///< see cwbvh_unpack: a kernel parameter, not a literal
};

/// Closest or any hit of `ray`, the triangle named by its scene-wide id (TwoLevelBvh). One loop
/// and one stack for both levels, so that lanes of a warp in the TLAS and lanes in a BLAS run
/// the same instructions: a TLAS leaf (one instance: build_two_level makes them so) is ordered
/// and stacked like a child node; taken, it moves the ray into the instance's space and walks
/// the instance's BLAS on the same stack above `blas_base`, and when the stack falls back to
/// that mark the ray returns to the world. (Nesting the BVH2 walk in the TLAS walk traced
/// diffuse rays at half the speed: lanes waited for each other's levels, experiments/NOTES.md.)
/// Counters add up both levels.
template <bool kAnyHit>
BVHLAB_HD inline Hit traverse_two_level(const TwoLevelView& v, const Ray& ray, TraversalCounters* counters = nullptr) {
    Hit hit = Hit::miss();
    float tmax = ray.tmax;
    Vec3 o = ray.org, d = ray.dir, inv = safe_reciprocal(ray.dir);
    const accel::Bvh2Node* nodes = v.tlas;
    Bvh2View blas{nullptr, nullptr, nullptr};
    uint32_t first_id = 0;
    int32_t stack[2 * kBvh2StackSize];
    int sp = 0;
    int blas_base = -1;  // the stack height when the current BLAS began; -1 in the TLAS
    int32_t node = 0;    // a node of the current level, or (< 0, in the TLAS) an instance's leaf
    while (true) {
        if (node < 0) {  // enter the instance of a TLAS leaf
            if (counters) ++counters->leaves;
            const accel::InstanceRecord& inst = v.instances[v.tlas_ids[accel::Bvh2Node::leaf_first(node)]];
            o = inst.point(ray.org);
            d = inst.vector(ray.dir);
            inv = safe_reciprocal(d);
            blas = v.blas[inst.blas];
            nodes = blas.nodes;
            first_id = inst.first_id;
            blas_base = sp;
            node = 0;
        }
        const accel::Bvh2Node& n = nodes[node];
        if (counters) ++counters->nodes;
        const float t0 =
            slab_entry(n.c0_lo_x, n.c0_hi_x, n.c0_lo_y, n.c0_hi_y, n.c0_lo_z, n.c0_hi_z, o, inv, ray.tmin, tmax);
        const float t1 =
            slab_entry(n.c1_lo_x, n.c1_hi_x, n.c1_lo_y, n.c1_hi_y, n.c1_lo_z, n.c1_hi_z, o, inv, ray.tmin, tmax);
        int32_t next[2];
        float tnext[2];
        int nnext = 0;
        for (int c = 0; c < 2; ++c) {
            const float tc = c == 0 ? t0 : t1;
            if (tc == INFINITY) continue;
            const int32_t ref = n.child[c];
            if (ref >= 0 || blas_base < 0) {  // a node, or an instance to enter in its turn
                next[nnext] = ref;
                tnext[nnext++] = tc;
                continue;
            }
            if (counters) ++counters->leaves;
            const uint32_t first = accel::Bvh2Node::leaf_first(ref);
            const uint32_t end = first + accel::Bvh2Node::leaf_count(ref);
            for (uint32_t k = first; k < end; ++k) {
                if (counters) ++counters->tri_tests;
                float t, u, w;
                if (blas.tris[k].intersect(o, d, ray.tmin, tmax, t, u, w)) {
                    hit = {int32_t(first_id + blas.tri_ids[k]), t, u, w};
                    tmax = t;
                    if (kAnyHit) return hit;
                }
            }
        }
        if (nnext == 2) {
            const bool swap = tnext[1] < tnext[0];
            stack[sp++] = next[swap ? 0 : 1];
            node = next[swap ? 1 : 0];
            continue;
        }
        if (nnext == 1) {
            node = next[0];
            continue;
        }
        if (sp == blas_base) {  // the BLAS is done: back to the world
            blas_base = -1;
            nodes = v.tlas;
            o = ray.org;
            d = ray.dir;
            inv = safe_reciprocal(ray.dir);
        }
        if (sp == 0) break;
        node = stack[--sp];
    }
    return hit;
}

}  // namespace bvhlab::trav
