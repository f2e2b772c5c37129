// SPDX-License-Identifier: MIT
// Owning, move-only device arrays in plain C++ (tiny-cuda-nn's GPUMemory, CUB's d_ pointers):
// callers never include CUDA headers. The few runtime calls it needs live in runtime.cu, or
// in runtime_stub.cpp, which throws, in builds without CUDA.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace bvhlab::trav {

/// True when this build has CUDA and a device is usable; otherwise `why` gets the reason.
bool gpu_available(std::string* why = nullptr);
/// The CUDA devices this process sees (after CUDA_VISIBLE_DEVICES); 0 without CUDA or a driver.
int gpu_count();
/// Device name, compute capability and SM count, e.g. "NVIDIA H100 80GB HBM3 (sm_90, 132 SMs)".
std::string gpu_description();
/// The NVIDIA kernel driver version (from /proc/driver/nvidia/version), else the CUDA driver
/// API version, e.g. "580.159.04" or "CUDA 13.0".
std::string gpu_driver();
/// The device's current and maximum SM clocks in MHz (NVML is not needed: the runtime's
/// clockRate is the maximum; the current one comes from the driver when it says).
struct SmClock {
    int current_mhz = 0;  ///< 0 when the driver does not say
    int max_mhz = 0;
};
SmClock gpu_sm_clock();
/// Multiprocessors of the current device.
int gpu_sm_count();
/// Device memory this process holds through DeviceBuffer (structures, ray queues, render
/// buffers; not the CUDA context), now and at most since it began. Zero without CUDA.
struct GpuMemoryUse {
    size_t current = 0;
    size_t peak = 0;
};
GpuMemoryUse gpu_memory_use();

namespace detail {
void* device_malloc(size_t bytes);                 ///< throws bvhlab::CudaError naming the size on failure
void device_free(void* p, size_t bytes) noexcept;  ///< bytes: what device_malloc was asked for
void copy_to_device(void* d_dst, const void* h_src, size_t bytes);
void copy_to_host(void* h_dst, const void* d_src, size_t bytes);
void fill_device_bytes(void* d_dst, uint8_t value, size_t bytes, void* stream = nullptr);  ///< async on stream
}  // namespace detail

/// `size()` elements of trivially copyable T in device memory. Move-only; frees on destruction.
template <typename T>
class DeviceBuffer {
    static_assert(std::is_trivially_copyable_v<T>, "device buffers hold plain data");

public:
    DeviceBuffer() = default;
    explicit DeviceBuffer(size_t n) { resize(n); }
    explicit DeviceBuffer(const std::vector<T>& h_data) { upload(h_data); }
    DeviceBuffer(const DeviceBuffer&) = delete;
    DeviceBuffer& operator=(const DeviceBuffer&) = delete;
    DeviceBuffer(DeviceBuffer&& o) noexcept
        : d_ptr_(std::exchange(o.d_ptr_, nullptr)), size_(std::exchange(o.size_, 0)) {}
    DeviceBuffer& operator=(DeviceBuffer&& o) noexcept {
        if (this != &o) {
            release();
            d_ptr_ = std::exchange(o.d_ptr_, nullptr);
            size_ = std::exchange(o.size_, 0);
        }
        return *this;
    }
    ~DeviceBuffer() { release(); }

    /// Reallocates to n elements when the size changes; the contents are then undefined.
    void resize(size_t n) {
        if (n == size_) return;
        release();
        if (n) d_ptr_ = static_cast<T*>(detail::device_malloc(n * sizeof(T)));
        size_ = n;
    }
    void upload(const std::vector<T>& h_data) {
        resize(h_data.size());
        if (size_) detail::copy_to_device(d_ptr_, h_data.data(), bytes());
    }
    /// Copies the first n elements (all by default) to the host.
    void download(std::vector<T>& h_out, size_t n = size_t(-1)) const {
        h_out.resize(n < size_ ? n : size_);
        if (!h_out.empty()) detail::copy_to_host(h_out.data(), d_ptr_, h_out.size() * sizeof(T));
    }
    /// Sets every byte (asynchronously on `stream`, the default stream when null).
    void fill_bytes(uint8_t value, void* stream = nullptr) {
        if (size_) detail::fill_device_bytes(d_ptr_, value, bytes(), stream);
    }

    T* data() { return d_ptr_; }
    const T* data() const { return d_ptr_; }
    size_t size() const { return size_; }
    size_t bytes() const { return size_ * sizeof(T); }
    bool empty() const { return size_ == 0; }

private:
    void release() noexcept {
        if (d_ptr_) detail::device_free(d_ptr_, bytes());
        d_ptr_ = nullptr;
        size_ = 0;
    }
    T* d_ptr_ = nullptr;
    size_t size_ = 0;
};

/// Kernel time between two device events on one stream (CUDA events), move-only.
class DeviceTimer {
public:
    DeviceTimer();
    ~DeviceTimer();
    DeviceTimer(const DeviceTimer&) = delete;
    DeviceTimer& operator=(const DeviceTimer&) = delete;
    void start(void* stream = nullptr);
    /// Records the stop event, waits for it and returns the milliseconds since start().
    float stop(void* stream = nullptr);

private:
    void* start_ = nullptr;
    void* stop_ = nullptr;
};

}  // namespace bvhlab::trav
