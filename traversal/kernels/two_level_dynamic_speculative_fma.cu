// SPDX-License-Identifier: MIT
// Kernel 'two-level-dynamic-speculative-fma': dynamic-speculative-fma over instanced scenes; the
// two-level layout's default (on 100 turned bunnies 1.22x 'two-level' on primary rays and 1.68x on
// diffuse ones, experiments/NOTES.md).
#include "traversal/kernels/while_while_launch.cuh"

namespace bvhlab::trav {

BVHLAB_REGISTER_KERNEL({"two-level-dynamic-speculative-fma", Layout::kTwoLevel,
                        "instanced scenes: dynamic-speculative-fma over the TLAS and each instance's BLAS on one stack "
                        "(persistent threads; idle lanes start new rays once 8 of 32 are idle, --fetch-threshold)",
                        kBvh2StackSize, false, 128, launch_two_level_while_while<true, Fetch::kDynamic>, 1024, true,
                        /*counts=*/false, /*is_default=*/true});

}  // namespace bvhlab::trav
