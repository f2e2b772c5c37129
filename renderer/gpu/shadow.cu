// SPDX-License-Identifier: MIT
// Stage "shadow": the unoccluded shadow rays add their radiance (after the any-hit trace).
#include <algorithm>

#include "renderer/gpu/launch.cuh"
#include "renderer/gpu/stage_kernels.h"
#include "traversal/gpu/device_buffer.h"

namespace bvhlab::render::gpu {
namespace {

__global__ void resolve_kernel(const trav::Hit* occ, const uint32_t* slot, const Vec3* rad, Vec3* radiance,
                               const uint32_t* count, uint32_t capacity, Chores chores) {
    do_chores(chores);
    const uint32_t n = min(*count, capacity);
    for (uint32_t i = blockIdx.x * blockDim.x + threadIdx.x; i < n; i += gridDim.x * blockDim.x)
        resolve_shadow(i, occ, slot, rad, radiance);
}

}  // namespace

void launch_resolve_shadow(const trav::Hit* occlusion, const uint32_t* slot, const Vec3* shadow_radiance,
                           Vec3* radiance, const uint32_t* d_count, uint32_t capacity, const Chores& chores,
                           void* stream) {
    // A grid-stride loop over a grid of at most 16 blocks per SM: the count is on the device,
    // and most bounces' shadow queues are a fraction of the capacity the grid was sized for
    // (7,200 mostly empty blocks, 7.1 us per launch on the Cornell box; NOTES.md, session 16).
    static const uint32_t max_blocks = 16u * uint32_t(trav::gpu_sm_count());
    resolve_kernel<<<std::min(stage_blocks(capacity), max_blocks), kStageBlock, 0, as_stream(stream)>>>(
        occlusion, slot, shadow_radiance, radiance, d_count, capacity, chores);
    BVHLAB_CHECK_LAUNCH();
}

}  // namespace bvhlab::render::gpu
