// SPDX-License-Identifier: MIT
// Kernel 'while-while': Aila-Laine while-while: separate loops for interior nodes and leaf tests, one thread per ray, 16-byte read-only loads.
#include "traversal/device/bvh2_while_while.cuh"
#include "traversal/kernels/launch_helpers.cuh"

namespace bvhlab::trav {
namespace {

void launch(const LaunchArgs& a) {
    for_query(a, [&](auto any) {
        launch_per_ray(a, 128, WhileWhileTrace<decltype(any)::value, false, false>{a.bvh2});
    });
}

}  // namespace

BVHLAB_REGISTER_KERNEL({"while-while", Layout::kBvh2, "Aila-Laine while-while: separate loops for interior nodes and leaf tests, one thread per ray, 16-byte read-only loads", kBvh2StackSize, false, 128, launch});

}  // namespace bvhlab::trav
