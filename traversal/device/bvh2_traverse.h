// SPDX-License-Identifier: MIT
// Stack-based traversal of a Bvh2 with Woop triangles, written once for host and device.
// Near child first; leaves are tested as soon as their box is hit.
#pragma once

#include <cstdint>

#include "accel/core/build_tree.h"
#include "accel/core/hd.h"
#include "accel/layouts/bvh2_node.h"
#include "traversal/device/ray.h"

namespace bvhlab::trav {

/// Stack entries of the shared traversal. Trees deeper than this (Bvh2::depth) are refused by
/// the tracers before any ray is traced; builders stay below it (BuildConfig::max_depth).
constexpr int kBvh2StackSize = int(accel::kMaxTreeDepth);
static_assert(kBvh2StackSize >= int(accel::kMaxTreeDepth), "the BVH2 stack must hold the deepest tree a builder makes");

/// Per-ray work counters, filled when a non-null pointer is given.
struct TraversalCounters {
    uint32_t nodes = 0;      ///< interior nodes fetched
    uint32_t leaves = 0;     ///< leaves whose box the ray entered
    uint32_t tri_tests = 0;  ///< triangle intersection tests
    uint32_t restarts = 0;   ///< short-stack restarts from the root (kd-tree short stack)
};

/// A BVH2 layout as traversal sees it: plain pointers, host or device memory.
struct Bvh2View {
    const accel::Bvh2Node* nodes;
    const accel::WoopTriangle* tris;
    const uint32_t* tri_ids;  ///< mesh triangle id of each entry of tris
};

/// Reciprocal with Aila & Laine's guard: components closer to 0 than 2^-80 are clamped, so
/// slab distances stay finite (never 0 * inf = NaN).
BVHLAB_HD BVHLAB_FORCEINLINE Vec3 safe_reciprocal(Vec3 d) {
    const float eps = 8.271806e-25f;  // 2^-80
    auto inv = [eps](float x) { return 1.0f / (fabsf(x) > eps ? x : copysignf(eps, x)); };
    return {inv(d.x), inv(d.y), inv(d.z)};
}

/// Entry distance into a box, or +inf when the ray misses it within [tmin, tmax]. The exit
/// distance is widened by 2 ulp-scale units so rays grazing a flat box are not lost to
/// rounding (Ize 2013, "Robust BVH ray traversal").
BVHLAB_HD BVHLAB_FORCEINLINE float slab_entry(float lox, float hix, float loy, float hiy, float loz, float hiz, Vec3 o,
                                              Vec3 inv, float tmin, float tmax) {
    const float x0 = (lox - o.x) * inv.x, x1 = (hix - o.x) * inv.x;
    const float y0 = (loy - o.y) * inv.y, y1 = (hiy - o.y) * inv.y;
    const float z0 = (loz - o.z) * inv.z, z1 = (hiz - o.z) * inv.z;
    // The safe reciprocal keeps every slab distance a number (never NaN), so plain
    // compare-select min/max are exact here.
    const float tn = max_f(max_f(min_f(x0, x1), min_f(y0, y1)), max_f(min_f(z0, z1), tmin));
    const float tf = min_f(min_f(max_f(x0, x1), max_f(y0, y1)), max_f(z0, z1)) * 1.0000004f;
    return tn <= min_f(tf, tmax) ? tn : INFINITY;
}

/// Closest hit (kAnyHit = false) or any hit (kAnyHit = true) of `ray`.
template <bool kAnyHit>
BVHLAB_HD inline Hit traverse_bvh2(const accel::Bvh2Node* nodes, const accel::WoopTriangle* tris,
                                   const uint32_t* tri_ids, const Ray& ray, TraversalCounters* counters = nullptr) {
    Hit hit = Hit::miss();
    float tmax = ray.tmax;
    const Vec3 o = ray.org, d = ray.dir, inv = safe_reciprocal(ray.dir);
    int32_t stack[kBvh2StackSize];
    int sp = 0;
    int32_t node = 0;
    while (true) {
        const accel::Bvh2Node& n = nodes[node];
        if (counters) ++counters->nodes;
        float t0 = slab_entry(n.c0_lo_x, n.c0_hi_x, n.c0_lo_y, n.c0_hi_y, n.c0_lo_z, n.c0_hi_z, o, inv, ray.tmin, tmax);
        float t1 = slab_entry(n.c1_lo_x, n.c1_hi_x, n.c1_lo_y, n.c1_hi_y, n.c1_lo_z, n.c1_hi_z, o, inv, ray.tmin, tmax);
        int32_t next[2];
        float tnext[2];
        int nnext = 0;
        for (int c = 0; c < 2; ++c) {
            const float tc = c == 0 ? t0 : t1;
            if (tc == INFINITY) continue;
            const int32_t ref = n.child[c];
            if (ref >= 0) {
                next[nnext] = ref;
                tnext[nnext++] = tc;
                continue;
            }
            if (counters) ++counters->leaves;
            const uint32_t first = accel::Bvh2Node::leaf_first(ref);
            const uint32_t end = first + accel::Bvh2Node::leaf_count(ref);
            for (uint32_t k = first; k < end; ++k) {
                if (counters) ++counters->tri_tests;
                float t, u, v;
                if (tris[k].intersect(o, d, ray.tmin, tmax, t, u, v)) {
                    hit = {int32_t(tri_ids[k]), t, u, v};
                    tmax = t;
                    if (kAnyHit) return hit;
                }
            }
        }
        if (nnext == 2) {
            // Visit the nearer child first; the farther one waits on the stack.
            const bool swap = tnext[1] < tnext[0];
            stack[sp++] = next[swap ? 0 : 1];
            node = next[swap ? 1 : 0];
        } else if (nnext == 1) {
            node = next[0];
        } else {
            if (sp == 0) break;
            node = stack[--sp];
        }
    }
    return hit;
}

/// The same over a view.
template <bool kAnyHit>
BVHLAB_HD BVHLAB_FORCEINLINE Hit traverse_bvh2(const Bvh2View& v, const Ray& ray,
                                               TraversalCounters* counters = nullptr) {
    return traverse_bvh2<kAnyHit>(v.nodes, v.tris, v.tri_ids, ray, counters);
}

}  // namespace bvhlab::trav
