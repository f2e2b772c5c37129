// SPDX-License-Identifier: MIT
// The first-hit cache: at bounce 0 of every pass after the first, the camera rays' hits come
// from the pixels' cached hits instead of a trace (camera_rays_repeat guarantees they are the
// same rays).
#include "renderer/gpu/launch.cuh"
#include "renderer/gpu/stage_kernels.h"

namespace bvhlab::render::gpu {
namespace {

__global__ void cached_hits_kernel(const trav::Hit* first_hits, uint32_t npix, trav::Hit* hits, const uint32_t* count,
                                   uint32_t capacity) {
    const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i < capacity && i < *count) hits[i] = first_hits[i % npix];
}

}  // namespace

void launch_cached_hits(const trav::Hit* first_hits, uint32_t npix, trav::Hit* hits, const uint32_t* d_count,
                        uint32_t capacity, void* stream) {
    if (capacity == 0) return;
    cached_hits_kernel<<<stage_blocks(capacity), kStageBlock, 0, as_stream(stream)>>>(first_hits, npix, hits, d_count,
                                                                                      capacity);
    BVHLAB_CHECK_LAUNCH();
}

}  // namespace bvhlab::render::gpu
