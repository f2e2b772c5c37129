// SPDX-License-Identifier: MIT
// Kernel 'while-while-fma-shared-stack': while-while-fma with the stack in shared memory (65 words per thread) instead
// of local memory.
#include "traversal/kernels/while_while_launch.cuh"

namespace bvhlab::trav {

BVHLAB_REGISTER_KERNEL({"while-while-fma-shared-stack", Layout::kBvh2,
                        "while-while-fma with the stack in shared memory (65 words per thread) instead of local memory",
                        kBvh2StackSize, false, 128, launch_while_while<false, true, Fetch::kPerRay, true>});

}  // namespace bvhlab::trav
