// SPDX-License-Identifier: MIT
// Kernel 'dynamic-speculative-fma': speculative-fma in persistent threads with dynamic fetch: idle lanes start new rays
// once 8 of the warp's 32 are idle (--fetch-threshold).
#include "traversal/kernels/while_while_launch.cuh"

namespace bvhlab::trav {

BVHLAB_REGISTER_KERNEL({"dynamic-speculative-fma", Layout::kBvh2,
                        "speculative-fma in persistent threads with dynamic fetch: idle lanes start new rays once 8 of "
                        "the warp's 32 are idle (--fetch-threshold)",
                        kBvh2StackSize, false, 128, launch_while_while<true, true, Fetch::kDynamic>, 1024, true,
                        /*counts=*/false, /*is_default=*/true});

}  // namespace bvhlab::trav
