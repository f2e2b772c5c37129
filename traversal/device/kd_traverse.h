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
/// Factors that widen a split plane's distance t = (split - o) * (1 / d) by its rounding bound
/// (3 roundings: 3 x 2^-24 relative) plus the rounding of the product itself: 1 + 3 x 2^-23
/// and 1 - 7 x 2^-24, about +-4e-7 (the widening of slab_entry's exit, Ize 2013).
constexpr float kKdSplitHi = 1.0000004f;
constexpr float kKdSplitLo = 0.9999996f;

/// A kd-tree as traversal sees it. `tris` holds one Woop triangle per mesh triangle id.
struct KdView {
    const accel::KdNode* nodes;
    const uint32_t* prims;
    const accel::WoopTriangle* tris;
    AABB bounds;
};

/// Closest or any hit with a stack of `stack_limit` entries (1 .. kCap). A short stack whose
/// restart stalls (below) retries with all kCap entries for the rest of the ray.
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
    // A short stack restarts; a full one never does, and keeps no restart state.
    constexpr bool kRestarts = kCap <= kKdMaxShortStack;
    struct Entry {
        uint32_t node;
        float tmin, tmax;
    };
    Entry stack[kCap];
    int top = -1, count = 0, limit = stack_limit;
    bool dropped = false;            // a push overwrote an entry since the last (re)start
    float restarted_at = -INFINITY;  // the farthest leaf exit a restart has resumed after
    uint32_t node = 0, last_leaf = ~0u;
    float tn = t_enter, tf = t_exit;
    // The widened tests below, t_split- < tf and tn < t_split+, as thresholds on t_split that
    // change only with the interval (at a push, pop or restart), not at every node:
    // t_split < tf_c = tf x Hi and tn_c = tn x Lo < t_split (each as conservative as the
    // product form, to within an ulp of the widening's 2x margin).
    float tn_c = tn * kKdSplitLo, tf_c = tf * kKdSplitHi;
    while (true) {
        while (!kd.nodes[node].is_leaf()) {
            const accel::KdNode& n = kd.nodes[node];
            if (counters) ++counters->nodes;
            const int k = int(n.axis());
            const float split = n.split();
            const float t_split = (split - o[k]) * inv[k];
            const bool below_first = o[k] < split || (o[k] == split && d[k] <= 0.0f);
            const uint32_t near = n.child() + (below_first ? 0u : 1u), far = n.child() + (below_first ? 1u : 0u);
            // The ray is on the near side for t < t_split and on the far side after it, but
            // t_split is rounded (a subtraction, a reciprocal and a product: at most 3 ulps)
            // and so is every cell boundary before it. A cell one or two ulps thick, such as the
            // cell between the two planes of a triangle that is flat to an ulp, has entry and
            // exit distances that round to the same float: an exact test would skip it and the
            // triangles that only it holds. So each side's interval is widened by the rounding
            // bound, [tn, t_split+] for the near side and [t_split-, tf] for the far side, and
            // a side is entered when its widened interval has length: near when tn < t_split+,
            // far when t_split- < tf. (After an exact restart, below, the near test is
            // tn < t_split, so a restart at a plane's t_split+ goes on past that plane.)
            // Computed in this order, t_split has the sign of the true distance, so a plane
            // behind the origin (t_split <= 0) is never crossed.
            if (t_split <= 0.0f || !(t_split < tf_c)) {
                node = near;
            } else if (!(tn_c < t_split)) {
                node = far;
            } else {
                top = (top + 1) % limit;  // overwrites the oldest entry when full
                stack[top] = {far, max_f(t_split * kKdSplitLo, tn), tf};
                dropped = dropped || count == limit;
                count = count < limit ? count + 1 : limit;
                node = near;
                tf = min_f(t_split * kKdSplitHi, tf);
                tf_c = tf * kKdSplitHi;
            }
        }
        const accel::KdNode& leaf = kd.nodes[node];
        if (counters) ++counters->leaves;
        // After a restart the ray may reach the leaf it left last again (below): its
        // triangles were tested then.
        const uint32_t n_tris = kRestarts && node == last_leaf ? 0u : leaf.count();
        if (kRestarts) last_leaf = node;
        for (uint32_t i = leaf.first(); i < leaf.first() + n_tris; ++i) {
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
            top = (top - 1 + limit) % limit;
            --count;
            if (e.tmin > best) return hit;
            node = e.node;
            tn = e.tmin;
            tf = e.tmax;
            tn_c = tn * kKdSplitLo;
            tf_c = tf * kKdSplitHi;
        } else if (kRestarts && dropped && tf < t_exit && tf < best) {
            // Entries were dropped (short stack): restart from the root past this leaf. The
            // dropped entries were the oldest, i.e. the farthest, so nothing before tf is lost.
            // tf is the widened exit t_split+ of some plane; a cell beyond it thinner than the
            // rounding window (between planes an ulp apart) ends before t_split+ as computed,
            // and planes within rounding of each other need not be in their true order. So the
            // ray first resumes where a pushed far side would have begun, at t_split- (and
            // passes through the leaf it left, without testing it again). If that reaches no
            // leaf ending past the farthest exit resumed after so far, it resumes exactly at
            // that exit instead, where every leaf it reaches ends later (near sides then need
            // tn < t_split); but first, once per ray, it retries conservatively with the whole
            // ring of kCap entries. Each conservative restart moves restarted_at forward, and
            // at most two others come between two of them, so restarts end.
            if (counters) ++counters->restarts;
            if (tf > restarted_at) {
                restarted_at = tf;
                tn = tf * (kKdSplitLo * kKdSplitLo);
                tn_c = tn * kKdSplitLo;
            } else if (limit < kCap) {
                // The re-descent dropped the entries of the cells it had to reach (many cells
                // within rounding of one another, a deep tree, a tiny stack): the stack is
                // empty now, so retry from the same place with all kCap entries.
                limit = kCap;
                top = -1;
                tn = restarted_at * (kKdSplitLo * kKdSplitLo);
                tn_c = tn * kKdSplitLo;
            } else {
                tn = tn_c = restarted_at;  // exact: near sides need t_split > tn
            }
            node = 0;
            tf = t_exit;
            tf_c = tf * kKdSplitHi;
            dropped = false;
        } else {
            return hit;
        }
    }
}

}  // namespace bvhlab::trav
