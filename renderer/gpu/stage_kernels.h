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

/// Bookkeeping that the first thread of a stage kernel does besides the stage: per-bounce
/// totals and the counters later stages need at zero. Each is a launch saved (a 1-thread kernel
/// or a memset costs 2-3 us of GPU time between dependent kernels; NOTES.md, session 16).
struct Chores {
    unsigned long long* total[2] = {nullptr, nullptr};  ///< total[k] += *count[k] where both are set
    const uint32_t* count[2] = {nullptr, nullptr};
    uint32_t* zero[2] = {nullptr, nullptr};  ///< set to 0 where set
    uint32_t* zero_run = nullptr;            ///< zero_run[0 .. zero_run_n) set to 0
    uint32_t zero_run_n = 0;
};

/// generate.cu: the camera rays of the pass's first `paths_n` slots; sets *d_count to paths_n
/// and does `chores`.
void launch_generate(const CameraData& cam, const PathParams& p, PathView paths, uint32_t paths_n, uint32_t* d_count,
                     const Chores& chores, void* stream);

/// Where the shade stage writes: the next bounce's paths and the shadow rays, each queue with
/// its device count (zeroed before the launch; the kernel reserves places with atomics).
struct NextQueues {
    PathView paths;  ///< ray, throughput, prev_pdf, slot (hit unused)
    uint32_t* count;
    trav::Ray* shadow_ray;
    Vec3* shadow_radiance;
    uint32_t* shadow_slot;
    uint32_t* shadow_count;
    /// Null: compact (the default). Otherwise every entry keeps its place, dead ones as
    /// placeholders, both queues keep the current count, and the live paths and shadow rays are
    /// counted here instead ([0] and [1]).
    uint32_t* live_counts;
};

/// shade.cu: shade() for i < *d_count, path order[i] (or i when order is null), its results
/// compacted into `q` (compact.cuh) or kept in place (q.live_counts).
void launch_shade(uint32_t bounce, const SceneView& s, const PathParams& p, PathView paths, const uint32_t* order,
                  NextQueues q, Vec3* radiance, Vec3* albedo, Vec3* normal, const uint32_t* d_count, uint32_t capacity,
                  const Chores& chores, void* stream);

/// sort.cu: the buffers of the material sort, each of the wave's capacity, and CUB's scratch.
struct MaterialSortBuffers {
    uint32_t *keys_in, *keys_out, *order_in, *order_out;
    void* temp;
    size_t temp_bytes;
    int bits;  ///< material_sort_bits
};

/// The key bits a sort over `materials` materials needs (misses, the default material, the
/// mesh's, and the past-the-end key).
int material_sort_bits(size_t materials);

/// CUB's scratch bytes for a sort of `capacity` keys of `bits` bits.
size_t material_sort_temp_bytes(uint32_t capacity, int bits);

/// sort.cu: b.order_out = the entries i < *d_count ordered by the material of hits[i], stably
/// (misses first), then the entries past the count.
void launch_material_sort(const trav::Hit* hits, const int32_t* material_ids, const uint32_t* d_count,
                          uint32_t capacity, const MaterialSortBuffers& b, void* stream);

/// cache.cu: hits[i] = first_hits[i % npix] for i < *d_count (the first-hit cache at bounce 0,
/// where entry i is slot i).
void launch_cached_hits(const trav::Hit* first_hits, uint32_t npix, trav::Hit* hits, const uint32_t* d_count,
                        uint32_t capacity, void* stream);

/// shadow.cu: resolve_shadow for i < *d_count.
void launch_resolve_shadow(const trav::Hit* occlusion, const uint32_t* slot, const Vec3* shadow_radiance,
                           Vec3* radiance, const uint32_t* d_count, uint32_t capacity, const Chores& chores,
                           void* stream);

/// accumulate.cu: accumulate_pixel for every pixel, over the pass's `samples` slots of each.
void launch_accumulate(Vec3* radiance, const Vec3* albedo, const Vec3* normal, const PixelSums& sums, uint32_t npix,
                       uint32_t samples, void* stream);

}  // namespace bvhlab::render::gpu
