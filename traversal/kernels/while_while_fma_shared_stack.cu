// SPDX-License-Identifier: MIT
// Kernel 'while-while-fma-shared-stack': while-while-fma with the traversal stack in shared
// memory (65 words per thread, bank-conflict free) instead of local memory.
#include "traversal/device/bvh2_while_while.cuh"
#include "traversal/kernels/launch_helpers.cuh"

namespace bvhlab::trav {
namespace {

void launch(const LaunchArgs& a) {
    for_query(a, [&](auto any) {
        launch_per_ray(a, 128, WhileWhileTrace<decltype(any)::value, false, true, true>{a.bvh2},
                       ww_detail::kSharedStackBytes);
    });
}

}  // namespace

BVHLAB_REGISTER_KERNEL({"while-while-fma-shared-stack", Layout::kBvh2,
                        "while-while-fma with the stack in shared memory (65 words per thread) instead of local memory",
                        kBvh2StackSize, false, 128, launch});

}  // namespace bvhlab::trav
