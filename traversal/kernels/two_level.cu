// SPDX-License-Identifier: MIT
// Kernel 'two-level': instanced scenes. One thread per ray running the traversal the CPU tracer
// runs (traverse_two_level: one loop and one stack for both levels; at an instance the ray moves
// into the instance's space and the mesh's BLAS is walked above a stack mark, generic loads).
#include "traversal/kernels/launch_helpers.cuh"

namespace bvhlab::trav {
namespace {

template <bool kAnyHit>
struct TwoLevelTrace {
    TwoLevelView view;
    __device__ __forceinline__ Hit operator()(const Ray& r, TraversalCounters* c = nullptr) const {
        return traverse_two_level<kAnyHit>(view, r, c);
    }
};

void launch(const LaunchArgs& a) {
    for_query(a, [&](auto any) { launch_per_ray(a, 128, TwoLevelTrace<decltype(any)::value>{a.two_level}); });
}

}  // namespace

BVHLAB_REGISTER_KERNEL({"two-level", Layout::kTwoLevel,
                        "instanced scenes: one thread per ray, the CPU tracer's two-level traversal (one loop and one "
                        "stack for both levels, the ray moved into each instance's space)",
                        kBvh2StackSize, false, 128, launch, 1024, false, /*counts=*/true});

}  // namespace bvhlab::trav
