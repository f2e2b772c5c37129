// SPDX-License-Identifier: MIT
// Stage "shade" with the compaction fused in (compact.cuh): what each path sees, and its
// shadow ray and continuation written to their places in the next queues.
#include "renderer/gpu/compact.cuh"
#include "renderer/gpu/launch.cuh"
#include "renderer/gpu/stage_kernels.h"

namespace bvhlab::render::gpu {
namespace {

__global__ void __launch_bounds__(kStageBlock)
    shade_kernel(uint32_t bounce, SceneView s, PathParams p, PathView paths, NextQueues q, Vec3* radiance, Vec3* albedo,
                 Vec3* normal, const uint32_t* count) {
    using Compactor = BlockCompactor<kStageBlock>;
    __shared__ typename Compactor::Storage storage;
    const uint32_t n = *count;
    if (blockIdx.x * kStageBlock >= n) return;  // the whole block: no thread reaches the scan
    const uint32_t i = blockIdx.x * kStageBlock + threadIdx.x;
    ShadeResult r;
    r.alive = r.shadow = false;
    if (i < n) r = shade(i, bounce, s, p, paths, radiance, albedo, normal);
    uint32_t at, shadow_at;
    Compactor::places(storage, r.alive, r.shadow, q.count, q.shadow_count, at, shadow_at);
    if (r.alive) {
        q.paths.ray[at] = r.next_ray;
        q.paths.throughput[at] = r.next_throughput;
        q.paths.prev_pdf[at] = r.next_pdf;
        q.paths.slot[at] = paths.slot[i];
    }
    if (r.shadow) {
        q.shadow_ray[shadow_at] = r.shadow_ray;
        q.shadow_radiance[shadow_at] = r.shadow_radiance;
        q.shadow_slot[shadow_at] = paths.slot[i];
    }
}

}  // namespace

void launch_shade(uint32_t bounce, const SceneView& s, const PathParams& p, PathView paths, NextQueues q,
                  Vec3* radiance, Vec3* albedo, Vec3* normal, const uint32_t* d_count, uint32_t capacity,
                  void* stream) {
    if (capacity == 0) return;
    shade_kernel<<<stage_blocks(capacity), kStageBlock, 0, as_stream(stream)>>>(bounce, s, p, paths, q, radiance,
                                                                                albedo, normal, d_count);
    BVHLAB_CHECK_LAUNCH();
}

}  // namespace bvhlab::render::gpu
