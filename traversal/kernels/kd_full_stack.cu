// SPDX-License-Identifier: MIT
// Kernel 'kd-full-stack': the kd-tree reference on the GPU, one thread per ray running the
// shared traverse_kd with a full stack of 64 entries.
#include "traversal/device/kd_traverse.h"
#include "traversal/kernels/launch_helpers.cuh"

namespace bvhlab::trav {
namespace {

template <bool kAnyHit>
struct KdFullTrace {
    KdView view;
    __device__ __forceinline__ Hit operator()(const Ray& r, TraversalCounters* c = nullptr) const {
        return traverse_kd<kAnyHit, kKdFullStack>(view, r, kKdFullStack, c);
    }
};

void launch(const LaunchArgs& a) {
    for_query(a, [&](auto any) { launch_per_ray(a, 128, KdFullTrace<decltype(any)::value>{a.kd}); });
}

}  // namespace

BVHLAB_REGISTER_KERNEL({"kd-full-stack", Layout::kKd,
                        "kd-tree, one thread per ray, full stack of 64 (tmin, tmax, node) entries: the reference",
                        kKdFullStack, false, 128, launch, 1024, false, true, /*is_default=*/true});

}  // namespace bvhlab::trav
