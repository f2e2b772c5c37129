// SPDX-License-Identifier: MIT
// kd-tree traversal, host and device: a full stack, or a short stack with restart (Horn,
// Sugerman, Houston & Hanrahan 2007, "Interactive k-d tree GPU raytracing"). The stack is a
// ring of `stack_limit` entries; when pushes overflow it, the oldest entries are dropped, and
// once it runs dry the ray restarts at the root with tmin moved to the last leaf's exit.
#pragma once

#include <cstdint>

#include "accel/core/build_tree.h"
#include "accel/core/hd.h"
#include "accel/layouts/kd_node.h"
#include "accel/layouts/woop_tri.h"
#include "traversal/device/bvh2_traverse.h"
#include "traversal/device/ray.h"

namespace bvhlab::trav {

/// Full-stack entries; deeper trees are refused by the tracers.
constexpr int kKdFullStack = int(accel::kMaxTreeDepth);
static_assert(kKdFullStack >= int(accel::kMaxTreeDepth), "the kd full stack must hold the deepest kd-tree");
constexpr int kKdMaxShortStack = 8;

/// A kd-tree as traversal sees it. `tris` holds one Woop triangle per mesh triangle id.
struct KdView {
    const accel::KdNode* nodes;
    const uint32_t* prims;
    const accel::WoopTriangle* tris;
    AABB bounds;
};

/// Closest or any hit with a stack of `stack_limit` entries (1 .. kCap).
template <bool kAnyHit, int kCap>
BVHLAB_HD inline Hit traverse_kd(const KdView& kd, const Ray& ray, int stack_limit,
                                 TraversalCounters* counters = nullptr) {
    Hit hit = Hit::miss();
    float best = ray.tmax;
    const Vec3 o = ray.org, d = ray.dir, inv = safe_reciprocal(ray.dir);
    const float t_enter = slab_entry(kd.bounds.lo.x, kd.bounds.hi.x, kd.bounds.lo.y, kd.bounds.hi.y, kd.bounds.lo.z,
                                     kd.bounds.hi.z, o, inv, ray.tmin, ray.tmax);
    if (t_enter == INFINITY) return hit;
    // Exit distance of the scene box, widened like slab_entry's so flat scenes are not lost.
    float t_exit = ray.tmax;
    for (int k = 0; k < 3; ++k) {
        const float a = (kd.bounds.lo[k] - o[k]) * inv[k], b = (kd.bounds.hi[k] - o[k]) * inv[k];
        t_exit = min_f(t_exit, max_f(a, b) * 1.0000004f);
    }
    struct Entry {
        uint32_t node;
        float tmin, tmax;
    };
    Entry stack[kCap];
    int top = -1, count = 0;
    bool dropped = false;            // a push overwrote an entry since the last (re)start
    float restarted_at = -INFINITY;  // guards against restarts that make no progress
    uint32_t node = 0;
    float tn = t_enter, tf = t_exit;
    while (true) {
        while (!kd.nodes[node].is_leaf()) {
            const accel::KdNode& n = kd.nodes[node];
            if (counters) ++counters->nodes;
            const int k = int(n.axis());
            const float split = n.split();
            const float t_split = (split - o[k]) * inv[k];
            const bool below_first = o[k] < split || (o[k] == split && d[k] <= 0.0f);
            const uint32_t near = n.child() + (below_first ? 0u : 1u), far = n.child() + (below_first ? 1u : 0u);
            if (t_split > tf || t_split <= 0.0f) {
                node = near;
            } else if (t_split <= tn) {
                // Also when equal: the near side would be the single point tn, which after a
                // restart at a plane sends short-stack traversal into zero-length leaves.
                node = far;
            } else {
                top = (top + 1) % stack_limit;  // overwrites the oldest entry when full
                stack[top] = {far, t_split, tf};
                dropped = dropped || count == stack_limit;
                count = count < stack_limit ? count + 1 : stack_limit;
                node = near;
                tf = t_split;
            }
        }
        const accel::KdNode& leaf = kd.nodes[node];
        if (counters) ++counters->leaves;
        for (uint32_t i = leaf.first(); i < leaf.first() + leaf.count(); ++i) {
            if (counters) ++counters->tri_tests;
            const uint32_t id = kd.prims[i];
            float t, u, v;
            if (kd.tris[id].intersect(o, d, ray.tmin, best, t, u, v)) {
                hit = {int32_t(id), t, u, v};
                best = t;
                if (kAnyHit) return hit;
            }
        }
        // A hit inside this leaf's interval cannot be beaten by any later leaf.
        if (hit.is_hit() && best <= tf) return hit;
        if (count > 0) {
            const Entry e = stack[top];
            top = (top - 1 + stack_limit) % stack_limit;
            --count;
            if (e.tmin > best) return hit;
            node = e.node;
            tn = e.tmin;
            tf = e.tmax;
        } else if (dropped && tf < t_exit && tf < best && tf > restarted_at) {
            // Entries were dropped (short stack): restart from the root past this leaf. The
            // dropped entries were the oldest, i.e. the farthest, so nothing before tf is lost.
            if (counters) ++counters->restarts;
            node = 0;
            tn = restarted_at = tf;
            tf = t_exit;
            dropped = false;
        } else {
            return hit;
        }
    }
}

}  // namespace bvhlab::trav
