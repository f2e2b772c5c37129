// SPDX-License-Identifier: MIT
// Kernel 'kd-short-stack': kd-tree traversal with a short stack of 1-8 entries and restart
// (Horn, Sugerman, Houston & Hanrahan 2007), the shared traverse_kd. Any depth fits: entries
// that overflow the ring are dropped and the ray restarts from the root past its last leaf.
#include "traversal/device/kd_traverse.h"
#include "traversal/kernels/launch_helpers.cuh"

namespace bvhlab::trav {
namespace {

template <bool kAnyHit>
struct KdShortTrace {
    KdView view;
    int entries;
    __device__ __forceinline__ Hit operator()(const Ray& r, TraversalCounters* c = nullptr) const {
        return traverse_kd<kAnyHit, kKdMaxShortStack>(view, r, entries, c);
    }
};

void launch(const LaunchArgs& a) {
    for_query(a, [&](auto any) { launch_per_ray(a, 128, KdShortTrace<decltype(any)::value>{a.kd, a.kd_stack}); });
}

}  // namespace

BVHLAB_REGISTER_KERNEL(
    {"kd-short-stack", Layout::kKd,
     "kd-tree, one thread per ray, short stack of 1-8 entries (--kd-stack) with restart (Horn et al. 2007)",
     kNoStackLimit, true, 128, launch, 1024, false, true, /*is_default=*/true});

}  // namespace bvhlab::trav
