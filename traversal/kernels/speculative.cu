// SPDX-License-Identifier: MIT
// Kernel 'speculative': while-while with postponed leaf tests: lanes keep traversing until every lane of the warp has a
// leaf (warp vote).
#include "traversal/kernels/while_while_launch.cuh"

namespace bvhlab::trav {

BVHLAB_REGISTER_KERNEL(
    {"speculative", Layout::kBvh2,
     "while-while with postponed leaf tests: lanes keep traversing until every lane of the warp has a leaf (warp vote)",
     kBvh2StackSize, false, 128, launch_while_while<true, false, Fetch::kPerRay, false>});

}  // namespace bvhlab::trav
