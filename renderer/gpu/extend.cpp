// SPDX-License-Identifier: MIT
// Stage "extend" (and the shadow stage's trace): a registry kernel over a device ray queue.
#include "renderer/gpu/extend.h"

namespace bvhlab::render::gpu {

void extend(const trav::DeviceStructure& structure, const trav::KernelInfo& kernel, trav::RayQueue& queue,
            trav::Query query, uint32_t* next_ray, const trav::GpuTraceOptions& opts, void* stream) {
    trav::launch_on_queue(structure, kernel, queue, query, next_ray, opts, stream);
}

}  // namespace bvhlab::render::gpu
