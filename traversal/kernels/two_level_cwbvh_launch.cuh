// SPDX-License-Identifier: MIT
// The two-level-cwbvh traversal (traversal/device/two_level_cwbvh_traverse.h) as a resumable
// functor in the dynamic-fetch wrapper, for the kernel 'two-level-dynamic-cwbvh' and its
// measured variants (experiments/kernels/).
#pragma once

#include "traversal/device/two_level_cwbvh_traverse.h"
#include "traversal/kernels/launch_helpers.cuh"

namespace bvhlab::trav {

template <bool kAnyHit, bool kVertexTris>
struct TwoLevelDynamicCwbvhTrace {
    using State = TwoLevelCwbvhState;
    using Stack = TwoLevelCwbvhStack;
    TwoLevelView view;
    __device__ __forceinline__ void start(State& s, Stack&, const Ray& r) const { two_level_cwbvh_start(view, s, r); }
    __device__ __forceinline__ void step(State& s, Stack& stack) const {
        two_level_cwbvh_step<kAnyHit, kVertexTris>(view, s, stack, nullptr);
    }
    __device__ __forceinline__ bool done(const State& s) const { return two_level_cwbvh_done(s); }
    __device__ __forceinline__ Hit result(const State& s) const { return two_level_cwbvh_result(s); }
};

/// Launches it for the query and the BLAS's triangle format; kMinBlocks > 0 holds the kernel
/// to __launch_bounds__(128, kMinBlocks).
template <int kMinBlocks>
void launch_two_level_dynamic_cwbvh(const LaunchArgs& a) {
    for_query(a, [&](auto any) {
        const uint32_t threshold = a.fetch_threshold ? a.fetch_threshold : kDefaultFetchThreshold;
        if (a.two_level.cw_vertices)
            launch_dynamic_fetch<128, kMinBlocks>(
                a, 128, TwoLevelDynamicCwbvhTrace<decltype(any)::value, true>{a.two_level}, threshold);
        else
            launch_dynamic_fetch<128, kMinBlocks>(
                a, 128, TwoLevelDynamicCwbvhTrace<decltype(any)::value, false>{a.two_level}, threshold);
    });
}

}  // namespace bvhlab::trav
