// SPDX-License-Identifier: MIT
#pragma once

#include "traversal/gpu/gpu_tracer.h"
#include "traversal/gpu/ray_queue.h"

namespace bvhlab::render::gpu {

/// Traces the first *count rays of `queue` (count in device memory) with `kernel`, into the
/// queue's hits. `next_ray` is the persistent kernels' fetch counter, which must be zero
/// (the driver zeroes one per trace of a pass at once, in the generate kernel). Asynchronous
/// on `stream`.
void extend(const trav::DeviceStructure& structure, const trav::KernelInfo& kernel, trav::RayQueue& queue,
            trav::Query query, uint32_t* next_ray, const trav::GpuTraceOptions& opts, void* stream);

}  // namespace bvhlab::render::gpu
