// SPDX-License-Identifier: MIT
// Kernel 'plain': the baseline. One thread per ray running the traversal the CPU tracer runs
// (traverse_bvh2: near child first, leaves tested as soon as reached, generic loads).
#include "traversal/kernels/launch_helpers.cuh"

namespace bvhlab::trav {
namespace {

template <bool kAnyHit>
struct PlainTrace {
    Bvh2View view;
    __device__ __forceinline__ Hit operator()(const Ray& r, TraversalCounters* c = nullptr) const {
        return traverse_bvh2<kAnyHit>(view, r, c);
    }
};

void launch(const LaunchArgs& a) {
    for_query(a, [&](auto any) { launch_per_ray(a, 128, PlainTrace<decltype(any)::value>{a.bvh2}); });
}

}  // namespace

BVHLAB_REGISTER_KERNEL(
    {"plain", Layout::kBvh2,
     "baseline: one thread per ray, the traversal the CPU tracer runs (near child first, generic loads)",
     kBvh2StackSize, false, 128, launch, 1024, false, true});

}  // namespace bvhlab::trav
