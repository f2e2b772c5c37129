// SPDX-License-Identifier: MIT
// The GPU tracer: one registered kernel over one uploaded structure and one ray queue.
#pragma once

#include <memory>

#include "traversal/gpu/device_structure.h"
#include "traversal/gpu/registry.h"
#include "traversal/tracer.h"

namespace bvhlab::trav {

struct GpuTraceOptions {
    int kd_stack = 4;         ///< short-stack entries for kernels that take one (1..8)
    int block_size = 0;       ///< threads per block; 0 = the kernel's default
    int fetch_threshold = 0;  ///< dynamic-fetch kernels: idle lanes (1..32) that start new rays; 0 = default
};

/// Checks that `kernel` can trace `structure` (its layout, and a tree no deeper than the
/// kernel's stack) and that the options fit it; throws bvhlab::Error with a one-line reason.
void check_kernel_fits(const KernelInfo& kernel, Layout layout, uint32_t depth, const GpuTraceOptions& opts);

/// A GPU tracer; throws bvhlab::Error as check_kernel_fits does.
std::unique_ptr<Tracer> make_gpu_tracer(std::shared_ptr<const DeviceStructure> structure, const KernelInfo& kernel,
                                        const GpuTraceOptions& opts = {});

/// Traces the first `count` rays of a queue that already lives on the device with `kernel`
/// (no host copies): the entry point of a wavefront renderer. Asynchronous on `stream`.
/// `d_next_ray` is a device counter the caller zeroes before each launch (persistent kernels).
/// Traces `set` once with `kernel`, a kernel that counts (KernelInfo::counts: it runs a shared
/// traversal), and records each ray's work (nodes, leaves, triangle tests, restarts) in
/// `counters`, as the CPU tracers do. Runs the kernel's counting instance, not the timed one.
/// Throws bvhlab::Error for a kernel that does not count.
void trace_gpu_counted(const DeviceStructure& structure, const KernelInfo& kernel, const RaySet& set,
                       std::vector<Hit>& hits, std::vector<TraversalCounters>& counters,
                       const GpuTraceOptions& opts = {});

void launch_on_queue(const DeviceStructure& structure, const KernelInfo& kernel, RayQueue& queue, Query query,
                     uint32_t* d_next_ray, const GpuTraceOptions& opts = {}, void* stream = nullptr);

}  // namespace bvhlab::trav
