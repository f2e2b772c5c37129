// SPDX-License-Identifier: MIT
// Kernel 'two-level-dynamic-cwbvh': dynamic-cwbvh over instanced scenes whose BLAS are CWBVHs
// (layout two-level-cwbvh): persistent threads with dynamic fetch, a step is one TLAS node or one
// BLAS node and its triangles (traversal/device/two_level_cwbvh_traverse.h, the CPU's traversal).
#include "traversal/device/two_level_cwbvh_traverse.h"
#include "traversal/kernels/launch_helpers.cuh"

namespace bvhlab::trav {
namespace {

template <bool kAnyHit, bool kVertexTris>
struct TwoLevelDynamicCwbvhTrace {
    using State = TwoLevelCwbvhState;
    using Stack = TwoLevelCwbvhStack;
    TwoLevelView view;
    __device__ __forceinline__ void start(State& s, Stack&, const Ray& r) const { two_level_cwbvh_start(s, r); }
    __device__ __forceinline__ void step(State& s, Stack& stack) const {
        two_level_cwbvh_step<kAnyHit, kVertexTris>(view, s, stack, nullptr);
    }
    __device__ __forceinline__ bool done(const State& s) const { return two_level_cwbvh_done(s); }
    __device__ __forceinline__ Hit result(const State& s) const { return two_level_cwbvh_result(s); }
};

void launch(const LaunchArgs& a) {
    for_query(a, [&](auto any) {
        const uint32_t threshold = a.fetch_threshold ? a.fetch_threshold : kDefaultFetchThreshold;
        if (a.two_level.cw_vertices)
            launch_dynamic_fetch(a, 128, TwoLevelDynamicCwbvhTrace<decltype(any)::value, true>{a.two_level}, threshold);
        else
            launch_dynamic_fetch(a, 128, TwoLevelDynamicCwbvhTrace<decltype(any)::value, false>{a.two_level},
                                 threshold);
    });
}

}  // namespace

BVHLAB_REGISTER_KERNEL({"two-level-dynamic-cwbvh", Layout::kTwoLevelCwbvh,
                        "instanced scenes with CWBVH BLAS: dynamic-cwbvh over the TLAS and each instance's BLAS (a "
                        "step is one node of either level; idle lanes start new rays once 8 of 32 are idle, "
                        "--fetch-threshold)",
                        uint32_t(kBvh2StackSize), false, 128, launch, 1024, true, /*counts=*/false,
                        /*is_default=*/true});

}  // namespace bvhlab::trav
