// SPDX-License-Identifier: MIT
// The GPU wavefront driver (bvhlab render --device gpu): the stages of renderer/core/stages.h
// as one small kernel each, path state in device buffers, compaction by CUB, and the extend and
// shadow stages traced by any kernel of the registry over an uploaded structure. Within a
// sample pass nothing waits for the host: queue counts stay on the device, and every kernel
// is launched for the capacity. The host synchronises once per pass (progress, timing).
#pragma once

#include "renderer/wavefront.h"
#include "traversal/gpu/device_structure.h"
#include "traversal/gpu/gpu_tracer.h"
#include "traversal/gpu/registry.h"

namespace bvhlab::render {

/// Renders on the GPU with `kernel` tracing `structure` (the scene's triangles, ids as the
/// mesh's). Throws bvhlab::Error for bad settings, a kernel that does not fit the structure, or
/// a build without CUDA (the reason named).
RenderResult render_gpu(const RenderScene& scene, const CameraData& camera, const RenderSettings& settings,
                        const trav::DeviceStructure& structure, const trav::KernelInfo& kernel,
                        const trav::GpuTraceOptions& opts = {}, const RenderProgress& progress = {});

}  // namespace bvhlab::render
