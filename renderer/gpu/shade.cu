// SPDX-License-Identifier: MIT
// Stage "shade" with the compaction fused in (compact.cuh): what each path sees, and its
// shadow ray and continuation written to their places in the next queues.
#include "renderer/gpu/compact.cuh"
#include "renderer/gpu/launch.cuh"
#include "renderer/gpu/stage_kernels.h"

namespace bvhlab::render::gpu {
namespace {

/// A dead path's placeholder when the queues are not compacted: a ray no kernel can hit
/// anything with (tmax < tmin), zero throughput, so that shading its miss adds exactly 0.
__device__ inline trav::Ray placeholder_ray() { return {{0.0f, 0.0f, 0.0f}, 0.0f, {1.0f, 0.0f, 0.0f}, -1.0f}; }

__global__ void __launch_bounds__(kStageBlock)
    shade_kernel(uint32_t bounce, SceneView s, PathParams p, PathView paths, const uint32_t* order, NextQueues q,
                 Vec3* radiance, Vec3* albedo, Vec3* normal, const uint32_t* count, Chores chores) {
    using Compactor = BlockCompactor<kStageBlock>;
    __shared__ typename Compactor::Storage storage;
    do_chores(chores);
    const uint32_t n = *count;
    if (blockIdx.x * kStageBlock >= n) return;  // the whole block: no thread reaches the scan
    const uint32_t i = blockIdx.x * kStageBlock + threadIdx.x;
    const uint32_t j = order && i < n ? order[i] : i;  // the path this thread shades
    ShadeResult r;
    r.alive = r.shadow = false;
    if (i < n) r = shade(j, bounce, s, p, paths, radiance, albedo, normal);
    const bool compact = q.live_counts == nullptr;
    uint32_t at, shadow_at;
    // Without compaction the scan only counts: every entry keeps its place.
    Compactor::places(storage, r.alive, r.shadow, compact ? q.count : q.live_counts,
                      compact ? q.shadow_count : q.live_counts + 1, at, shadow_at);
    if (!compact) {
        if (i >= n) return;
        if (i == 0) *q.count = *q.shadow_count = n;
        at = shadow_at = i;
        if (!r.alive) {
            trav::store_ray(q.paths.ray, i, placeholder_ray());
            q.paths.throughput[i] = splat(0.0f);
            q.paths.prev_pdf[i] = 0.0f;
            q.paths.slot[i] = paths.slot[j];
        }
        if (!r.shadow) {
            trav::store_ray(q.shadow_ray, i, placeholder_ray());
            q.shadow_radiance[i] = splat(0.0f);
            q.shadow_slot[i] = paths.slot[j];
        }
    }
    if (r.alive) {
        trav::store_ray(q.paths.ray, at, r.next_ray);
        q.paths.throughput[at] = r.next_throughput;
        q.paths.prev_pdf[at] = r.next_pdf;
        q.paths.slot[at] = paths.slot[j];
    }
    if (r.shadow) {
        trav::store_ray(q.shadow_ray, shadow_at, r.shadow_ray);
        q.shadow_radiance[shadow_at] = r.shadow_radiance;
        q.shadow_slot[shadow_at] = paths.slot[j];
    }
}

}  // namespace

void launch_shade(uint32_t bounce, const SceneView& s, const PathParams& p, PathView paths, const uint32_t* order,
                  NextQueues q, Vec3* radiance, Vec3* albedo, Vec3* normal, const uint32_t* d_count, uint32_t capacity,
                  const Chores& chores, void* stream) {
    if (capacity == 0) return;
    shade_kernel<<<stage_blocks(capacity), kStageBlock, 0, as_stream(stream)>>>(bounce, s, p, paths, order, q, radiance,
                                                                                albedo, normal, d_count, chores);
    BVHLAB_CHECK_LAUNCH();
}

}  // namespace bvhlab::render::gpu
