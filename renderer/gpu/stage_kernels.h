// SPDX-License-Identifier: MIT
// Launchers of the GPU wavefront's stage kernels, one .cu file each (Laine, Karras & Aila
// 2013). Plain C++: streams travel as void*. Every launcher is asynchronous; a kernel that
// works on a queue is launched for the queue's capacity and reads the live count from device
// memory, so no count comes back to the host within a sample.
#pragma once

#include <cstddef>
#include <cstdint>

#include "renderer/core/stages.h"

namespace bvhlab::render::gpu {

/// generate.cu: the camera rays of the pass's first `paths_n` slots; sets *d_count to paths_n.
void launch_generate(const CameraData& cam, const PathParams& p, PathView paths, uint32_t paths_n, uint32_t* d_count,
                     void* stream);

/// shade.cu: shade_path for i < *d_count; clears the flags of the entries beyond it.
void launch_shade(uint32_t bounce, const SceneView& s, const PathParams& p, PathView paths, ShadeOut out,
                  Vec3* radiance, const uint32_t* d_count, uint32_t capacity, void* stream);

/// shadow.cu: resolve_shadow for i < *d_count.
void launch_resolve_shadow(const trav::Hit* occlusion, const uint32_t* slot, const Vec3* shadow_radiance,
                           Vec3* radiance, const uint32_t* d_count, uint32_t capacity, void* stream);

/// accumulate.cu: accumulate_pixel for every pixel, over the pass's `samples` slots of each.
void launch_accumulate(Vec3* radiance, const ShadeOut& aov, const PixelSums& sums, uint32_t npix, uint32_t samples,
                       void* stream);

/// compact.cu: the temporary bytes CUB's select needs for `capacity` flags.
size_t compact_temp_bytes(uint32_t capacity);
/// compact.cu: the indices of the set flags, in order, and their number in *d_count (CUB
/// DeviceSelect::Flagged over the whole capacity: the shade stage cleared the rest).
void launch_select(const uint8_t* flags, uint32_t* d_indices, uint32_t* d_count, uint32_t capacity, void* temp,
                   size_t temp_bytes, void* stream);
/// compact.cu: the live paths' continuations gathered by index into the next bounce's state.
void launch_gather_paths(const uint32_t* idx, const uint32_t* d_count, uint32_t capacity, ShadeOut in,
                         const uint32_t* slot_in, PathView out, void* stream);
/// compact.cu: the shadow rays gathered by index, with their slot and radiance.
void launch_gather_shadow(const uint32_t* idx, const uint32_t* d_count, uint32_t capacity, ShadeOut in,
                          const uint32_t* slot_in, trav::Ray* ray_out, uint32_t* slot_out, Vec3* radiance_out,
                          void* stream);
/// compact.cu: *d_total += *d_count (per-bounce ray counts, read once at the end).
void launch_add_count(const uint32_t* d_count, unsigned long long* d_total, void* stream);

}  // namespace bvhlab::render::gpu
