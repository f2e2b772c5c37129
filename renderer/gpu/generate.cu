// SPDX-License-Identifier: MIT
// Stage "generate": one camera ray per slot of the wave.
#include "renderer/gpu/launch.cuh"
#include "renderer/gpu/stage_kernels.h"

namespace bvhlab::render::gpu {
namespace {

__global__ void generate_kernel(CameraData cam, PathParams p, PathView paths, uint32_t n, uint32_t* count,
                                Chores chores) {
    const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    do_chores(chores);
    if (i == 0) *count = n;
    if (i < n) generate_path(i, cam, p, paths);
}

}  // namespace

void launch_generate(const CameraData& cam, const PathParams& p, PathView paths, uint32_t paths_n, uint32_t* d_count,
                     const Chores& chores, void* stream) {
    generate_kernel<<<stage_blocks(paths_n), kStageBlock, 0, as_stream(stream)>>>(cam, p, paths, paths_n, d_count,
                                                                                  chores);
    BVHLAB_CHECK_LAUNCH();
}

}  // namespace bvhlab::render::gpu
