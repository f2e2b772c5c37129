// SPDX-License-Identifier: MIT
// Kernel 'two-level-dynamic-cwbvh': dynamic-cwbvh over instanced scenes in the two-level-cwbvh
// layout (an 8-wide TLAS over CWBVH BLAS): persistent threads with dynamic fetch, a step is one
// 8-wide node of either level and its triangles or its first instance
// (traversal/device/two_level_cwbvh_traverse.h, the CPU's traversal).
#include "traversal/kernels/two_level_cwbvh_launch.cuh"

namespace bvhlab::trav {

BVHLAB_REGISTER_KERNEL({"two-level-dynamic-cwbvh", Layout::kTwoLevelCwbvh,
                        "instanced scenes, 8-wide TLAS and BLAS: dynamic-cwbvh over both levels on one stack (a "
                        "step is one node of either level; idle lanes start new rays once 8 of 32 are idle, "
                        "--fetch-threshold)",
                        uint32_t(kBvh2StackSize), false, 128, launch_two_level_dynamic_cwbvh<0>, 1024, true,
                        /*counts=*/false,
                        /*is_default=*/true});

}  // namespace bvhlab::trav
