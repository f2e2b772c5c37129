// SPDX-License-Identifier: MIT
// render_gpu in a build without CUDA.
#include "accel/core/check.h"
#include "renderer/gpu/gpu_render.h"

namespace bvhlab::render {

RenderResult render_gpu(const RenderScene&, const CameraData&, const RenderSettings&, const trav::DeviceStructure&,
                        const trav::KernelInfo&, const trav::GpuTraceOptions&, const RenderProgress&) {
    std::string why;
    trav::gpu_available(&why);
    throw Error("render --device gpu: " + why);
}

}  // namespace bvhlab::render
