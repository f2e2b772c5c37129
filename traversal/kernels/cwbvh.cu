// SPDX-License-Identifier: MIT
// Kernel 'cwbvh': the compressed 8-wide BVH (Ylitie, Karras & Laine 2017). One thread per ray
// running the traversal the CPU reference runs (traverse_cwbvh: octant-ordered node groups,
// triangle groups, five 16-byte node loads).
#include "traversal/kernels/launch_helpers.cuh"

namespace bvhlab::trav {
namespace {

template <bool kAnyHit, bool kVertexTris>
struct CwbvhTrace {
    CwbvhView view;
    __device__ __forceinline__ Hit operator()(const Ray& r, TraversalCounters* c = nullptr) const {
        return traverse_cwbvh<kAnyHit, kVertexTris>(view, r, c);
    }
};

void launch(const LaunchArgs& a) {
    for_cwbvh_query(a, [&](auto any, auto vertex_tris) {
        launch_per_ray(a, 128, CwbvhTrace<decltype(any)::value, decltype(vertex_tris)::value>{a.cwbvh});
    });
}

}  // namespace

BVHLAB_REGISTER_KERNEL({"cwbvh", Layout::kCwbvh,
                        "compressed 8-wide BVH: one thread per ray, the traversal the CPU reference runs "
                        "(octant-ordered node groups, quantised boxes)",
                        uint32_t(kCwbvhStackSize), false, 128, launch, 1024, false, true, /*is_default=*/true});

}  // namespace bvhlab::trav
