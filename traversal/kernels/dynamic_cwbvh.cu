// SPDX-License-Identifier: MIT
// Kernel 'dynamic-cwbvh': the cwbvh traversal in persistent threads with dynamic ray fetch
// inside the warp (Aila & Laine 2009, section 4): a step is one node fetch and its triangle
// tests, and idle lanes start new rays once --fetch-threshold (default 8) of the warp's 32 are idle.
#include "traversal/kernels/launch_helpers.cuh"

namespace bvhlab::trav {
namespace {

template <bool kAnyHit, bool kVertexTris>
struct DynamicCwbvhTrace {
    using State = CwbvhState;
    using Stack = CwbvhStack;
    CwbvhView view;
    __device__ __forceinline__ void start(State& s, Stack&, const Ray& r) const { cwbvh_start(s, r); }
    __device__ __forceinline__ void step(State& s, Stack& stack) const {
        cwbvh_step<kAnyHit, kVertexTris>(view, s, stack, nullptr);
    }
    __device__ __forceinline__ bool done(const State& s) const { return cwbvh_done(s); }
    __device__ __forceinline__ Hit result(const State& s) const { return cwbvh_result(view, s); }
};

void launch(const LaunchArgs& a) {
    for_cwbvh_query(a, [&](auto any, auto vertex_tris) {
        launch_dynamic_fetch(a, 128, DynamicCwbvhTrace<decltype(any)::value, decltype(vertex_tris)::value>{a.cwbvh},
                             a.fetch_threshold ? a.fetch_threshold : kDefaultFetchThreshold);
    });
}

}  // namespace

BVHLAB_REGISTER_KERNEL({"dynamic-cwbvh", Layout::kCwbvh,
                        "cwbvh in persistent threads with dynamic fetch: a step is one node and its triangles; idle "
                        "lanes start new rays once 8 of the warp's 32 are idle (--fetch-threshold)",
                        uint32_t(kCwbvhStackSize), false, 128, launch, 1024, true});

}  // namespace bvhlab::trav
