// SPDX-License-Identifier: MIT
// Per-bounce ray counts, added up on the device and read once per pass.
#include "renderer/gpu/launch.cuh"
#include "renderer/gpu/stage_kernels.h"

namespace bvhlab::render::gpu {
namespace {

__global__ void add_count_kernel(const uint32_t* count, unsigned long long* total) { *total += *count; }

}  // namespace

void launch_add_count(const uint32_t* d_count, unsigned long long* d_total, void* stream) {
    add_count_kernel<<<1, 1, 0, as_stream(stream)>>>(d_count, d_total);
    BVHLAB_CHECK_LAUNCH();
}

}  // namespace bvhlab::render::gpu
