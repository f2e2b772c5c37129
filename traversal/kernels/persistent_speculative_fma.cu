// SPDX-License-Identifier: MIT
// Kernel 'persistent-speculative-fma': speculative-fma in persistent threads: warps fetch 32 rays at a time from a global counter until the queue is empty.
#include "traversal/device/bvh2_while_while.cuh"
#include "traversal/kernels/launch_helpers.cuh"

namespace bvhlab::trav {
namespace {

void launch(const LaunchArgs& a) {
    for_query(a, [&](auto any) {
        launch_persistent(a, 128, WhileWhileTrace<decltype(any)::value, true, true>{a.bvh2});
    });
}

}  // namespace

BVHLAB_REGISTER_KERNEL({"persistent-speculative-fma", Layout::kBvh2, "speculative-fma in persistent threads: warps fetch 32 rays at a time from a global counter until the queue is empty", kBvh2StackSize, false, 128, launch});

}  // namespace bvhlab::trav
