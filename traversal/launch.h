// SPDX-License-Identifier: MIT
// Plain-C++ host API of the GPU tracer: callers never see CUDA headers or <<<>>>. Without
// CUDA in the build, gpu_available() says so and GpuBvh2 throws.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "accel/layouts/bvh2_node.h"
#include "traversal/device/ray.h"

namespace bvhlab::trav {

/// True when this build has CUDA and a device is usable; otherwise `why` gets the reason.
bool gpu_available(std::string* why = nullptr);

/// Device name, compute capability and SM count, e.g. "NVIDIA H100 80GB HBM3 (sm_90, 132 SMs)".
std::string gpu_description();

/// The NVIDIA kernel driver version (from /proc/driver/nvidia/version), else the CUDA driver
/// API version, e.g. "580.65.06" or "CUDA 13.0".
std::string gpu_driver();

/// A Bvh2 and a ray set resident on the GPU. Owns its device memory.
class GpuBvh2 {
public:
    /// Uploads nodes, Woop triangles and triangle ids. Throws bvhlab::Error (CudaError) on failure.
    explicit GpuBvh2(const accel::Bvh2& bvh);
    ~GpuBvh2();
    GpuBvh2(const GpuBvh2&) = delete;
    GpuBvh2& operator=(const GpuBvh2&) = delete;

    /// Uploads rays (replacing earlier ones) and sizes the hit buffer.
    void upload_rays(const std::vector<Ray>& rays);
    /// Traces the uploaded rays with the plain one-thread-per-ray kernel; returns the kernel
    /// time in milliseconds measured with CUDA events.
    float trace(Query query);
    /// Copies the last trace's hits to the host.
    void download_hits(std::vector<Hit>& hits) const;

    /// Convenience: upload, trace once, download.
    void trace(const std::vector<Ray>& rays, Query query, std::vector<Hit>& hits);

    struct Impl;  // device buffers; public only for the CUDA translation unit

private:
    std::unique_ptr<Impl> impl_;
};

}  // namespace bvhlab::trav
