// SPDX-License-Identifier: MIT
// Kernel 'persistent-while-while': while-while in persistent threads: warps fetch 32 rays at a time from a global counter until the queue is empty.
#include "traversal/device/bvh2_while_while.cuh"
#include "traversal/kernels/launch_helpers.cuh"

namespace bvhlab::trav {
namespace {

void launch(const LaunchArgs& a) {
    for_query(a, [&](auto any) {
        launch_persistent(a, 128, WhileWhileTrace<decltype(any)::value, false, false>{a.bvh2});
    });
}

}  // namespace

BVHLAB_REGISTER_KERNEL({"persistent-while-while", Layout::kBvh2, "while-while in persistent threads: warps fetch 32 rays at a time from a global counter until the queue is empty", kBvh2StackSize, false, 128, launch});

}  // namespace bvhlab::trav
