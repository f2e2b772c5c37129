// SPDX-License-Identifier: MIT
// Kernel 'persistent-speculative': speculative in persistent threads: warps fetch 32 rays at a time from a global
// counter until the queue is empty.
#include "traversal/kernels/while_while_launch.cuh"

namespace bvhlab::trav {

BVHLAB_REGISTER_KERNEL(
    {"persistent-speculative", Layout::kBvh2,
     "speculative in persistent threads: warps fetch 32 rays at a time from a global counter until the queue is empty",
     kBvh2StackSize, false, 128, launch_while_while<true, false, Fetch::kPersistent, false>});

}  // namespace bvhlab::trav
