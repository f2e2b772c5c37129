// SPDX-License-Identifier: MIT
// Stage "compact": CUB's DeviceSelect::Flagged turns the shade stage's flags into the indices
// of the live paths (or of the shadow rays) and writes their number straight into the next
// queue's device count; a gather kernel then packs the state.
#include <thrust/iterator/counting_iterator.h>
#include <cub/device/device_select.cuh>

#include "renderer/gpu/launch.cuh"
#include "renderer/gpu/stage_kernels.h"

namespace bvhlab::render::gpu {
namespace {

__global__ void gather_paths_kernel(const uint32_t* idx, const uint32_t* count, uint32_t capacity, ShadeOut in,
                                    const uint32_t* slot_in, PathView out) {
    const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= capacity || i >= *count) return;
    const uint32_t j = idx[i];
    out.ray[i] = in.next_ray[j];
    out.throughput[i] = in.next_throughput[j];
    out.prev_pdf[i] = in.next_pdf[j];
    out.slot[i] = slot_in[j];
}

__global__ void gather_shadow_kernel(const uint32_t* idx, const uint32_t* count, uint32_t capacity, ShadeOut in,
                                     const uint32_t* slot_in, trav::Ray* ray_out, uint32_t* slot_out,
                                     Vec3* radiance_out) {
    const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= capacity || i >= *count) return;
    const uint32_t j = idx[i];
    ray_out[i] = in.shadow_ray[j];
    radiance_out[i] = in.shadow_radiance[j];
    slot_out[i] = slot_in[j];
}

__global__ void add_count_kernel(const uint32_t* count, unsigned long long* total) { *total += *count; }

}  // namespace

size_t compact_temp_bytes(uint32_t capacity) {
    size_t bytes = 0;
    BVHLAB_CUDA_CHECK(cub::DeviceSelect::Flagged(nullptr, bytes, thrust::counting_iterator<uint32_t>(0),
                                                 static_cast<const uint8_t*>(nullptr), static_cast<uint32_t*>(nullptr),
                                                 static_cast<uint32_t*>(nullptr), int(capacity)));
    return bytes;
}

void launch_select(const uint8_t* flags, uint32_t* d_indices, uint32_t* d_count, uint32_t capacity, void* temp,
                   size_t temp_bytes, void* stream) {
    BVHLAB_CUDA_CHECK(cub::DeviceSelect::Flagged(temp, temp_bytes, thrust::counting_iterator<uint32_t>(0), flags,
                                                 d_indices, d_count, int(capacity), as_stream(stream)));
}

void launch_gather_paths(const uint32_t* idx, const uint32_t* d_count, uint32_t capacity, ShadeOut in,
                         const uint32_t* slot_in, PathView out, void* stream) {
    gather_paths_kernel<<<stage_blocks(capacity), kStageBlock, 0, as_stream(stream)>>>(idx, d_count, capacity, in,
                                                                                       slot_in, out);
    BVHLAB_CHECK_LAUNCH();
}

void launch_gather_shadow(const uint32_t* idx, const uint32_t* d_count, uint32_t capacity, ShadeOut in,
                          const uint32_t* slot_in, trav::Ray* ray_out, uint32_t* slot_out, Vec3* radiance_out,
                          void* stream) {
    gather_shadow_kernel<<<stage_blocks(capacity), kStageBlock, 0, as_stream(stream)>>>(
        idx, d_count, capacity, in, slot_in, ray_out, slot_out, radiance_out);
    BVHLAB_CHECK_LAUNCH();
}

void launch_add_count(const uint32_t* d_count, unsigned long long* d_total, void* stream) {
    add_count_kernel<<<1, 1, 0, as_stream(stream)>>>(d_count, d_total);
    BVHLAB_CHECK_LAUNCH();
}

}  // namespace bvhlab::render::gpu
