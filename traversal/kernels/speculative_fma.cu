// SPDX-License-Identifier: MIT
// Kernel 'speculative-fma': speculative with one-FMA slab distances: near and far planes picked by the direction sign, per-axis rounding slack.
#include "traversal/device/bvh2_while_while.cuh"
#include "traversal/kernels/launch_helpers.cuh"

namespace bvhlab::trav {
namespace {

void launch(const LaunchArgs& a) {
    for_query(a, [&](auto any) {
        launch_per_ray(a, 128, WhileWhileTrace<decltype(any)::value, true, true>{a.bvh2});
    });
}

}  // namespace

BVHLAB_REGISTER_KERNEL({"speculative-fma", Layout::kBvh2, "speculative with one-FMA slab distances: near and far planes picked by the direction sign, per-axis rounding slack", kBvh2StackSize, false, 128, launch});

}  // namespace bvhlab::trav
