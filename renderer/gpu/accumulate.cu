// SPDX-License-Identifier: MIT
// Stage "accumulate": the pass's radiance slots into the per-pixel sums. The same sums as
// accumulate_pixel (renderer/core/stages.h), in the same order, but one thread per pixel
// *channel*: the Vec3 arrays read as floats, so a warp's loads are 32 consecutive floats
// instead of 3 strided loads per Vec3, and three times the threads hide the latency of the
// loop over the wave's samples. Per pixel it ran at 20% of memory throughput, 71 us per pass
// of 1.84M slots (NOTES.md, session 16).
#include "renderer/gpu/launch.cuh"
#include "renderer/gpu/stage_kernels.h"

namespace bvhlab::render::gpu {
namespace {

__global__ void accumulate_kernel(float* radiance, const float* albedo, const float* normal, float* sum, float* sum_sq,
                                  float* albedo_sum, float* normal_sum, uint32_t n, uint32_t samples) {
    const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;  // pixel i / 3, channel i % 3
    if (i >= n) return;
    float s1 = sum[i], s2 = sum_sq[i];
    for (uint32_t k = 0; k < samples; ++k) {
        const size_t at = size_t(k) * n + i;
        const float r = radiance[at];
        s1 = s1 + r;
        s2 = s2 + r * r;
        radiance[at] = 0.0f;
        if (albedo_sum) {
            albedo_sum[i] = albedo_sum[i] + albedo[at];
            normal_sum[i] = normal_sum[i] + normal[at];
        }
    }
    sum[i] = s1;
    sum_sq[i] = s2;
}

float* floats(Vec3* v) { return reinterpret_cast<float*>(v); }
const float* floats(const Vec3* v) { return reinterpret_cast<const float*>(v); }

}  // namespace

void launch_accumulate(Vec3* radiance, const Vec3* albedo, const Vec3* normal, const PixelSums& sums, uint32_t npix,
                       uint32_t samples, void* stream) {
    static_assert(sizeof(Vec3) == 3 * sizeof(float), "Vec3 arrays are read as floats");
    const uint32_t n = 3 * npix;
    accumulate_kernel<<<stage_blocks(n), kStageBlock, 0, as_stream(stream)>>>(
        floats(radiance), floats(albedo), floats(normal), floats(sums.sum), floats(sums.sum_sq),
        sums.albedo ? floats(sums.albedo) : nullptr, sums.normal ? floats(sums.normal) : nullptr, n, samples);
    BVHLAB_CHECK_LAUNCH();
}

}  // namespace bvhlab::render::gpu
