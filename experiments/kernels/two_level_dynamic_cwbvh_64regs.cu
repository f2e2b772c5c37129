// SPDX-License-Identifier: MIT
// Kernel 'two-level-dynamic-cwbvh-64regs': two-level-dynamic-cwbvh held to 64 registers
// (__launch_bounds__(128, 8)) for 8 resident blocks per SM instead of the 71 registers' 6.
#include "traversal/kernels/two_level_cwbvh_launch.cuh"

namespace bvhlab::trav {

BVHLAB_REGISTER_KERNEL({"two-level-dynamic-cwbvh-64regs", Layout::kTwoLevelCwbvh,
                        "two-level-dynamic-cwbvh held to 64 registers (__launch_bounds__(128, 8))",
                        uint32_t(kBvh2StackSize), false, 128, launch_two_level_dynamic_cwbvh<8>, 128, true});

}  // namespace bvhlab::trav
