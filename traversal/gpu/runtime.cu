// SPDX-License-Identifier: MIT
// The CUDA runtime behind device_buffer.h: allocation, copies, events and device queries.
#include <cuda_runtime.h>

#include <atomic>

#include <cctype>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "traversal/cuda_check.h"
#include "traversal/gpu/device_buffer.h"

namespace bvhlab::trav {

bool gpu_available(std::string* why) {
    int n = 0;
    const cudaError_t e = cudaGetDeviceCount(&n);
    if (e != cudaSuccess || n == 0) {
        if (why)
            *why = e != cudaSuccess ? std::string("no usable CUDA device: ") + cudaGetErrorString(e)
                                    : "no CUDA device found";
        return false;
    }
    return true;
}

int gpu_count() {
    int n = 0;
    return cudaGetDeviceCount(&n) == cudaSuccess ? n : 0;
}

std::string gpu_description() {
    int dev = 0;
    cudaDeviceProp p{};
    if (cudaGetDevice(&dev) != cudaSuccess || cudaGetDeviceProperties(&p, dev) != cudaSuccess) return "unknown GPU";
    return std::string(p.name) + " (sm_" + std::to_string(p.major) + std::to_string(p.minor) + ", " +
           std::to_string(p.multiProcessorCount) + " SMs)";
}

int gpu_sm_count() {
    int dev = 0, n = 0;
    BVHLAB_CUDA_CHECK(cudaGetDevice(&dev));
    BVHLAB_CUDA_CHECK(cudaDeviceGetAttribute(&n, cudaDevAttrMultiProcessorCount, dev));
    return n;
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

SmClock gpu_sm_clock() {
    SmClock c;
    int dev = 0, khz = 0;
    if (cudaGetDevice(&dev) == cudaSuccess && cudaDeviceGetAttribute(&khz, cudaDevAttrClockRate, dev) == cudaSuccess)
        c.max_mhz = khz / 1000;
    // The current clock is the driver's to tell; nvidia-smi asks NVML without linking it here
    // (a link would make every binary need libnvidia-ml, which CI machines lack).
    if (FILE* p = popen("nvidia-smi --query-gpu=clocks.sm --format=csv,noheader,nounits -i 0 2>/dev/null", "r")) {
        int mhz = 0;
        if (std::fscanf(p, "%d", &mhz) == 1) c.current_mhz = mhz;
        pclose(p);
    }
    return c;
}

namespace {
std::atomic<size_t> g_current{0}, g_peak{0};  // DeviceBuffer bytes held, and the most held
}  // namespace

GpuMemoryUse gpu_memory_use() { return {g_current.load(), g_peak.load()}; }

namespace detail {

void* device_malloc(size_t bytes) {
    void* p = nullptr;
    const cudaError_t e = cudaMalloc(&p, bytes);
    if (e != cudaSuccess) {
        cudaGetLastError();  // clear the sticky-free error state of a failed allocation
        throw CudaError("cannot allocate " + std::to_string(bytes) + " bytes of GPU memory: " + cudaGetErrorString(e));
    }
    const size_t now = g_current += bytes;
    size_t peak = g_peak.load();
    while (now > peak && !g_peak.compare_exchange_weak(peak, now)) {
    }
    return p;
}

void device_free(void* p, size_t bytes) noexcept {
    BVHLAB_CUDA_CHECK_LOG(cudaFree(p));
    g_current -= bytes;
}

void copy_to_device(void* d_dst, const void* h_src, size_t bytes) {
    BVHLAB_CUDA_CHECK(cudaMemcpy(d_dst, h_src, bytes, cudaMemcpyHostToDevice));
}

void copy_to_host(void* h_dst, const void* d_src, size_t bytes) {
    BVHLAB_CUDA_CHECK(cudaMemcpy(h_dst, d_src, bytes, cudaMemcpyDeviceToHost));
}

void fill_device_bytes(void* d_dst, uint8_t value, size_t bytes, void* stream) {
    BVHLAB_CUDA_CHECK(cudaMemsetAsync(d_dst, value, bytes, static_cast<cudaStream_t>(stream)));
}

}  // namespace detail

DeviceTimer::DeviceTimer() {
    cudaEvent_t a = nullptr, b = nullptr;
    BVHLAB_CUDA_CHECK(cudaEventCreate(&a));
    const cudaError_t e = cudaEventCreate(&b);
    if (e != cudaSuccess) {
        cudaEventDestroy(a);
        BVHLAB_CUDA_CHECK(e);
    }
    start_ = a;
    stop_ = b;
}

DeviceTimer::~DeviceTimer() {
    BVHLAB_CUDA_CHECK_LOG(cudaEventDestroy(static_cast<cudaEvent_t>(start_)));
    BVHLAB_CUDA_CHECK_LOG(cudaEventDestroy(static_cast<cudaEvent_t>(stop_)));
}

void DeviceTimer::start(void* stream) {
    BVHLAB_CUDA_CHECK(cudaEventRecord(static_cast<cudaEvent_t>(start_), static_cast<cudaStream_t>(stream)));
}

float DeviceTimer::stop(void* stream) {
    BVHLAB_CUDA_CHECK(cudaEventRecord(static_cast<cudaEvent_t>(stop_), static_cast<cudaStream_t>(stream)));
    BVHLAB_CUDA_CHECK(cudaEventSynchronize(static_cast<cudaEvent_t>(stop_)));
    // A kernel fault surfaces here at the latest, with the kernel's error, not a later call's.
    BVHLAB_CUDA_CHECK(cudaGetLastError());
    float ms = 0.0f;
    BVHLAB_CUDA_CHECK(cudaEventElapsedTime(&ms, static_cast<cudaEvent_t>(start_), static_cast<cudaEvent_t>(stop_)));
    return ms;
}

}  // namespace bvhlab::trav
