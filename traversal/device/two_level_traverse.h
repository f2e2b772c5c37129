// SPDX-License-Identifier: MIT
// Two-level traversal (accel/layouts/two_level.h), written once for host and device: the TLAS
// walk of bvh2_traverse.h over instances; at an instance the ray is moved into the instance's
// space (origin and direction through the inverse transform, so t keeps its meaning) and traced
// through the mesh's BLAS with the current closest t as its tmax.
#pragma once

#include "accel/layouts/two_level.h"
#include "traversal/device/bvh2_traverse.h"

namespace bvhlab::trav {

/// A two-level BVH as traversal sees it: plain pointers, host or device memory.
struct TwoLevelView {
    const accel::Bvh2Node* tlas;
    const uint32_t* tlas_ids;  ///< instance index of each TLAS leaf entry
    const accel::InstanceRecord* instances;
    const Bvh2View* blas;  ///< one view per BLAS
};

/// Closest or any hit of `ray`, the triangle named by its scene-wide id (TwoLevelBvh).
/// Counters add up both levels; `instances` (when given) counts the BLAS traversals.
template <bool kAnyHit>
BVHLAB_HD inline Hit traverse_two_level(const TwoLevelView& v, const Ray& ray, TraversalCounters* counters = nullptr,
                                        uint32_t* instances = nullptr) {
    return walk_bvh2(
        v.tlas, ray,
        [&](uint32_t first, uint32_t count, float& tmax, Hit& hit) {
            for (uint32_t k = first; k < first + count; ++k) {
                const accel::InstanceRecord& inst = v.instances[v.tlas_ids[k]];
                if (instances) ++*instances;
                Ray local = ray;
                local.org = inst.point(ray.org);
                local.dir = inst.vector(ray.dir);
                local.tmax = tmax;
                const Hit h = traverse_bvh2<kAnyHit>(v.blas[inst.blas], local, counters);
                if (h.is_hit()) {
                    hit = {int32_t(inst.first_id + uint32_t(h.tri)), h.t, h.u, h.v};
                    tmax = h.t;
                    if (kAnyHit) return true;
                }
            }
            return false;
        },
        counters);
}

}  // namespace bvhlab::trav
