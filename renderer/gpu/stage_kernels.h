// SPDX-License-Identifier: MIT
// Launchers of the GPU wavefront's stage kernels, one .cu file each (Laine, Karras & Aila
// 2013); the compaction is fused into the shade kernel (compact.cuh). Plain C++: streams travel as void*. Every
// launcher is asynchronous; a kernel that works on a queue is launched for the queue's capacity and reads the live
// count from device memory, so no count comes back to the host within a sample.
#pragma once

#include <cstddef>
#include <cstdint>

#include "renderer/core/stages.h"

namespace bvhlab::render::gpu {

/// generate.cu: the camera rays of the pass's first `paths_n` slots; sets *d_count to paths_n.
void launch_generate(const CameraData& cam, const PathParams& p, PathView paths, uint32_t paths_n, uint32_t* d_count,
                     void* stream);

/// Where the shade stage writes: the next bounce's paths and the shadow rays, each queue with
/// its device count (zeroed before the launch; the kernel reserves places with atomics).
struct NextQueues {
    PathView paths;  ///< ray, throughput, prev_pdf, slot (hit unused)
    uint32_t* count;
    trav::Ray* shadow_ray;
    Vec3* shadow_radiance;
    uint32_t* shadow_slot;
    uint32_t* shadow_count;
};

/// shade.cu: shade() for i < *d_count, its results compacted into `q` (compact.cuh).
void launch_shade(uint32_t bounce, const SceneView& s, const PathParams& p, PathView paths, NextQueues q,
                  Vec3* radiance, Vec3* albedo, Vec3* normal, const uint32_t* d_count, uint32_t capacity, void* stream);

/// shadow.cu: resolve_shadow for i < *d_count.
void launch_resolve_shadow(const trav::Hit* occlusion, const uint32_t* slot, const Vec3* shadow_radiance,
                           Vec3* radiance, const uint32_t* d_count, uint32_t capacity, void* stream);

/// accumulate.cu: accumulate_pixel for every pixel, over the pass's `samples` slots of each.
void launch_accumulate(Vec3* radiance, const Vec3* albedo, const Vec3* normal, const PixelSums& sums, uint32_t npix,
                       uint32_t samples, void* stream);

/// counts.cu: *d_total += *d_count (per-bounce ray counts, read once at the end).
void launch_add_count(const uint32_t* d_count, unsigned long long* d_total, void* stream);

}  // namespace bvhlab::render::gpu
