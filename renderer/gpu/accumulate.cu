// SPDX-License-Identifier: MIT
// Stage "accumulate": the pass's radiance slots into the per-pixel sums, one thread per pixel
// (accumulate_pixel). One thread per pixel channel, reading the Vec3 arrays as floats, was
// measured slower: 11 ms against 7 ms per 512-spp render on every scene (NOTES.md, session 16).
#include "renderer/gpu/launch.cuh"
#include "renderer/gpu/stage_kernels.h"

namespace bvhlab::render::gpu {
namespace {

__global__ void accumulate_kernel(Vec3* radiance, const Vec3* albedo, const Vec3* normal, PixelSums sums, uint32_t npix,
                                  uint32_t samples) {
    const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i < npix) accumulate_pixel(i, npix, samples, radiance, albedo, normal, sums);
}

}  // namespace

void launch_accumulate(Vec3* radiance, const Vec3* albedo, const Vec3* normal, const PixelSums& sums, uint32_t npix,
                       uint32_t samples, void* stream) {
    accumulate_kernel<<<stage_blocks(npix), kStageBlock, 0, as_stream(stream)>>>(radiance, albedo, normal, sums, npix,
                                                                                 samples);
    BVHLAB_CHECK_LAUNCH();
}

}  // namespace bvhlab::render::gpu
