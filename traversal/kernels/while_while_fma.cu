// SPDX-License-Identifier: MIT
// Kernel 'while-while-fma': while-while with one-FMA slab distances: near and far planes picked by the direction sign,
// per-axis rounding slack.
#include "traversal/kernels/while_while_launch.cuh"

namespace bvhlab::trav {

BVHLAB_REGISTER_KERNEL({"while-while-fma", Layout::kBvh2,
                        "while-while with one-FMA slab distances: near and far planes picked by the direction sign, "
                        "per-axis rounding slack",
                        kBvh2StackSize, false, 128, launch_while_while<false, true, Fetch::kPerRay, false>});

}  // namespace bvhlab::trav
