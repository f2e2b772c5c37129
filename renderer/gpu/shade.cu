// SPDX-License-Identifier: MIT
// Stage "shade": what each path sees, its shadow ray and its continuation.
#include "renderer/gpu/launch.cuh"
#include "renderer/gpu/stage_kernels.h"

namespace bvhlab::render::gpu {
namespace {

__global__ void shade_kernel(uint32_t bounce, SceneView s, PathParams p, PathView paths, ShadeOut out, Vec3* radiance,
                             const uint32_t* count, uint32_t capacity) {
    const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= capacity) return;
    if (i >= *count) {
        out.alive[i] = 0;
        out.shadow[i] = 0;
        return;
    }
    shade_path(i, bounce, s, p, paths, out, radiance);
}

}  // namespace

void launch_shade(uint32_t bounce, const SceneView& s, const PathParams& p, PathView paths, ShadeOut out,
                  Vec3* radiance, const uint32_t* d_count, uint32_t capacity, void* stream) {
    shade_kernel<<<stage_blocks(capacity), kStageBlock, 0, as_stream(stream)>>>(bounce, s, p, paths, out, radiance,
                                                                                d_count, capacity);
    BVHLAB_CHECK_LAUNCH();
}

}  // namespace bvhlab::render::gpu
