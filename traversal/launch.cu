// SPDX-License-Identifier: MIT
// GpuBvh2: device buffers, uploads, timed launches.
#include <cuda_runtime.h>

#include <cctype>
#include <fstream>
#include <sstream>

#include "traversal/cuda_check.h"
#include "traversal/kernels/trace_bvh2.h"
#include "traversal/launch.h"

namespace bvhlab::trav {

namespace {

/// Owning device array.
template <typename T>
struct DeviceArray {
    T* ptr = nullptr;
    size_t size = 0;
    void resize(size_t n) {
        if (n == size) return;
        release();
        if (n) BVHLAB_CUDA_CHECK(cudaMalloc(&ptr, n * sizeof(T)));
        size = n;
    }
    void upload(const std::vector<T>& h) {
        resize(h.size());
        if (size) BVHLAB_CUDA_CHECK(cudaMemcpy(ptr, h.data(), size * sizeof(T), cudaMemcpyHostToDevice));
    }
    void release() {
        if (ptr) BVHLAB_CUDA_CHECK_LOG(cudaFree(ptr));
        ptr = nullptr;
        size = 0;
    }
    ~DeviceArray() { release(); }
};

}  // namespace

struct GpuBvh2::Impl {
    DeviceArray<accel::Bvh2Node> d_nodes;
    DeviceArray<accel::WoopTriangle> d_tris;
    DeviceArray<uint32_t> d_tri_ids;
    DeviceArray<Ray> d_rays;
    DeviceArray<Hit> d_hits;
    cudaEvent_t start = nullptr, stop = nullptr;
};

bool gpu_available(std::string* why) {
    int n = 0;
    const cudaError_t e = cudaGetDeviceCount(&n);
    if (e != cudaSuccess || n == 0) {
        if (why) *why = e != cudaSuccess ? std::string("no usable CUDA device: ") + cudaGetErrorString(e)
                                         : "no CUDA device found";
        return false;
    }
    return true;
}

std::string gpu_description() {
    int dev = 0, driver = 0;
    cudaDeviceProp p{};
    if (cudaGetDevice(&dev) != cudaSuccess || cudaGetDeviceProperties(&p, dev) != cudaSuccess) return "unknown GPU";
    (void)driver;
    return std::string(p.name) + " (sm_" + std::to_string(p.major) + std::to_string(p.minor) + ", " +
           std::to_string(p.multiProcessorCount) + " SMs)";
}

std::string gpu_driver() {
    std::ifstream in("/proc/driver/nvidia/version");
    std::string line;
    if (std::getline(in, line)) {
        // "NVRM version: NVIDIA UNIX Open Kernel Module for x86_64  580.159.04  Release Build ...":
        // the first token of the form digits.digits is the version.
        std::istringstream ss(line);
        for (std::string tok; ss >> tok;)
            if (!tok.empty() && std::isdigit(static_cast<unsigned char>(tok[0])) && tok.find('.') != std::string::npos)
                return tok;
    }
    int driver = 0;
    cudaDriverGetVersion(&driver);
    return "CUDA " + std::to_string(driver / 1000) + "." + std::to_string((driver % 1000) / 10);
}

GpuBvh2::GpuBvh2(const accel::Bvh2& bvh) : impl_(std::make_unique<Impl>()) {
    std::string why;
    if (!gpu_available(&why)) throw CudaError(why);
    impl_->d_nodes.upload(bvh.nodes);
    impl_->d_tris.upload(bvh.tris);
    impl_->d_tri_ids.upload(bvh.tri_ids);
    BVHLAB_CUDA_CHECK(cudaEventCreate(&impl_->start));
    BVHLAB_CUDA_CHECK(cudaEventCreate(&impl_->stop));
}

GpuBvh2::~GpuBvh2() {
    if (impl_->start) BVHLAB_CUDA_CHECK_LOG(cudaEventDestroy(impl_->start));
    if (impl_->stop) BVHLAB_CUDA_CHECK_LOG(cudaEventDestroy(impl_->stop));
}

void GpuBvh2::upload_rays(const std::vector<Ray>& rays) {
    BVHLAB_CHECK(rays.size() < (size_t(1) << 32), "at most 2^32 rays per launch");
    impl_->d_rays.upload(rays);
    impl_->d_hits.resize(rays.size());
}

float GpuBvh2::trace(Query query) {
    BVHLAB_CUDA_CHECK(cudaEventRecord(impl_->start));
    launch_trace_bvh2(impl_->d_nodes.ptr, impl_->d_tris.ptr, impl_->d_tri_ids.ptr, impl_->d_rays.ptr,
                      impl_->d_hits.ptr, uint32_t(impl_->d_rays.size), query, nullptr);
    BVHLAB_CUDA_CHECK(cudaEventRecord(impl_->stop));
    BVHLAB_CUDA_CHECK(cudaEventSynchronize(impl_->stop));
    float ms = 0.0f;
    BVHLAB_CUDA_CHECK(cudaEventElapsedTime(&ms, impl_->start, impl_->stop));
    return ms;
}

void GpuBvh2::download_hits(std::vector<Hit>& hits) const {
    hits.resize(impl_->d_hits.size);
    if (!hits.empty())
        BVHLAB_CUDA_CHECK(cudaMemcpy(hits.data(), impl_->d_hits.ptr, hits.size() * sizeof(Hit), cudaMemcpyDeviceToHost));
}

void GpuBvh2::trace(const std::vector<Ray>& rays, Query query, std::vector<Hit>& hits) {
    upload_rays(rays);
    trace(query);
    download_hits(hits);
}

}  // namespace bvhlab::trav
