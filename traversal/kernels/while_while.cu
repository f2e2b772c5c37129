// SPDX-License-Identifier: MIT
// Kernel 'while-while': Aila-Laine while-while: separate loops for interior nodes and leaf tests, one thread per ray,
// 16-byte read-only loads.
#include "traversal/kernels/while_while_launch.cuh"

namespace bvhlab::trav {

BVHLAB_REGISTER_KERNEL({"while-while", Layout::kBvh2,
                        "Aila-Laine while-while: separate loops for interior nodes and leaf tests, one thread per ray, "
                        "16-byte read-only loads",
                        kBvh2StackSize, false, 128, launch_while_while<false, false, Fetch::kPerRay, false>});

}  // namespace bvhlab::trav
