// SPDX-License-Identifier: MIT
// Kernel 'two-level-while-while-fma': while-while-fma over instanced scenes, one thread per ray.
#include "traversal/kernels/while_while_launch.cuh"

namespace bvhlab::trav {

BVHLAB_REGISTER_KERNEL({"two-level-while-while-fma", Layout::kTwoLevel,
                        "instanced scenes: while-while-fma over the TLAS and each instance's BLAS on one stack, one "
                        "thread per ray",
                        kBvh2StackSize, false, 128, launch_two_level_while_while<false, Fetch::kPerRay>, 1024});

}  // namespace bvhlab::trav
