// SPDX-License-Identifier: MIT
// Optional stage "sort": the bounce's paths ordered by the material they hit, so that the
// shade kernel's warps run one BSDF at a time (the optimisation the reference CUDA path tracers
// measure). Keys: 0 for a miss, material id + 2 for a hit (the default material is 1), and
// the largest key for the entries past the live count, which sort last; CUB's radix sort over
// only the bits those keys need. Shade then reads path order[i] as its i-th.
#include <cub/device/device_radix_sort.cuh>

#include "renderer/gpu/launch.cuh"
#include "renderer/gpu/stage_kernels.h"

namespace bvhlab::render::gpu {
namespace {

__global__ void material_keys_kernel(const trav::Hit* hits, const int32_t* material_ids, const uint32_t* count,
                                     uint32_t capacity, uint32_t past_end, uint32_t* keys, uint32_t* order) {
    const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= capacity) return;
    uint32_t key = past_end;
    if (i < *count) {
        const trav::Hit h = hits[i];
        key = h.is_hit() ? uint32_t(material_ids[h.tri] + 2) : 0u;
    }
    keys[i] = key;
    order[i] = i;
}

}  // namespace

int material_sort_bits(size_t materials) {
    int bits = 1;
    while ((size_t(1) << bits) <= materials + 2) ++bits;
    return bits;
}

size_t material_sort_temp_bytes(uint32_t capacity, int bits) {
    size_t bytes = 0;
    BVHLAB_CUDA_CHECK(cub::DeviceRadixSort::SortPairs(
        nullptr, bytes, static_cast<const uint32_t*>(nullptr), static_cast<uint32_t*>(nullptr),
        static_cast<const uint32_t*>(nullptr), static_cast<uint32_t*>(nullptr), capacity, 0, bits));
    return bytes;
}

void launch_material_sort(const trav::Hit* hits, const int32_t* material_ids, const uint32_t* d_count,
                          uint32_t capacity, const MaterialSortBuffers& b, void* stream) {
    if (capacity == 0) return;
    const uint32_t past_end = (1u << b.bits) - 1u;
    material_keys_kernel<<<stage_blocks(capacity), kStageBlock, 0, as_stream(stream)>>>(
        hits, material_ids, d_count, capacity, past_end, b.keys_in, b.order_in);
    BVHLAB_CHECK_LAUNCH();
    size_t bytes = b.temp_bytes;
    BVHLAB_CUDA_CHECK(cub::DeviceRadixSort::SortPairs(b.temp, bytes, b.keys_in, b.keys_out, b.order_in, b.order_out,
                                                      capacity, 0, b.bits, as_stream(stream)));
}

}  // namespace bvhlab::render::gpu
