// SPDX-License-Identifier: MIT
// A ray queue on the device: rays, hits, and the ray count in device memory, so that a
// wavefront renderer can produce rays on the GPU and trace them without copying the count
// back. Kernels are launched for the queue's capacity and read the count themselves.
#pragma once

#include <cstdint>
#include <vector>

#include "traversal/device/ray.h"
#include "traversal/gpu/device_buffer.h"

namespace bvhlab::trav {

/// What a kernel sees of a queue: plain device pointers, host and device code alike.
struct RayQueueView {
    Ray* rays;        ///< capacity entries, the first *count in use
    Hit* hits;        ///< one per ray, written by the trace kernels
    uint32_t* count;  ///< in device memory
};

class RayQueue {
public:
    explicit RayQueue(size_t capacity = 0) { reserve(capacity); }

    /// Grows the buffers to hold `capacity` rays (contents are then lost).
    void reserve(size_t capacity);
    /// Copies rays in and sets the device count to rays.size() (growing the queue if needed).
    void upload(const std::vector<Ray>& rays);
    /// Sets the device count (at most the capacity); for producers that wrote rays themselves.
    void set_count(uint32_t count);
    /// Copies the first n hits out.
    void download_hits(std::vector<Hit>& out, size_t n) const { hits_.download(out, n); }
    /// Fills the hit buffer with 0x7F bytes (tri 0x7F7F7F7F, an id no mesh has), so that a
    /// kernel that leaves a hit unwritten is caught by the id check of the comparison.
    void poison_hits(void* stream = nullptr) { hits_.fill_bytes(0x7F, stream); }

    size_t capacity() const { return rays_.size(); }
    RayQueueView view() { return {rays_.data(), hits_.data(), count_.data()}; }

private:
    DeviceBuffer<Ray> rays_;
    DeviceBuffer<Hit> hits_;
    DeviceBuffer<uint32_t> count_;
};

}  // namespace bvhlab::trav
