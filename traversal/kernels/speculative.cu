// SPDX-License-Identifier: MIT
// Kernel 'speculative': while-while with postponed leaf tests: lanes keep traversing until every lane of the warp has a leaf (warp vote).
#include "traversal/device/bvh2_while_while.cuh"
#include "traversal/kernels/launch_helpers.cuh"

namespace bvhlab::trav {
namespace {

void launch(const LaunchArgs& a) {
    for_query(a, [&](auto any) {
        launch_per_ray(a, 128, WhileWhileTrace<decltype(any)::value, true, false>{a.bvh2});
    });
}

}  // namespace

BVHLAB_REGISTER_KERNEL({"speculative", Layout::kBvh2, "while-while with postponed leaf tests: lanes keep traversing until every lane of the warp has a leaf (warp vote)", kBvh2StackSize, false, 128, launch});

}  // namespace bvhlab::trav
