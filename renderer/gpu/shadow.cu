// SPDX-License-Identifier: MIT
// Stage "shadow": the unoccluded shadow rays add their radiance (after the any-hit trace).
#include "renderer/gpu/launch.cuh"
#include "renderer/gpu/stage_kernels.h"

namespace bvhlab::render::gpu {
namespace {

__global__ void resolve_kernel(const trav::Hit* occ, const uint32_t* slot, const Vec3* rad, Vec3* radiance,
                               const uint32_t* count, uint32_t capacity, Chores chores) {
    const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    do_chores(chores);
    if (i < capacity && i < *count) resolve_shadow(i, occ, slot, rad, radiance);
}

}  // namespace

void launch_resolve_shadow(const trav::Hit* occlusion, const uint32_t* slot, const Vec3* shadow_radiance,
                           Vec3* radiance, const uint32_t* d_count, uint32_t capacity, const Chores& chores,
                           void* stream) {
    resolve_kernel<<<stage_blocks(capacity), kStageBlock, 0, as_stream(stream)>>>(occlusion, slot, shadow_radiance,
                                                                                  radiance, d_count, capacity, chores);
    BVHLAB_CHECK_LAUNCH();
}

}  // namespace bvhlab::render::gpu
