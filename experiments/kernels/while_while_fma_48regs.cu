// SPDX-License-Identifier: MIT
// Kernel 'while-while-fma-48regs': while-while-fma held to 48 registers (__launch_bounds__(128, 10)) for 10 resident
// blocks per SM.
#include "traversal/kernels/while_while_launch.cuh"

namespace bvhlab::trav {

BVHLAB_REGISTER_KERNEL(
    {"while-while-fma-48regs", Layout::kBvh2,
     "while-while-fma held to 48 registers (__launch_bounds__(128, 10)) for 10 resident blocks per SM", kBvh2StackSize,
     false, 128, launch_while_while<false, true, Fetch::kPerRay, false, 10>, 128});

}  // namespace bvhlab::trav
