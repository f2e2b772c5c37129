// SPDX-License-Identifier: MIT
// The GPU runtime of a build without CUDA: every entry point says so.
#include "accel/core/check.h"
#include "traversal/gpu/device_buffer.h"
#include "traversal/gpu/gpu_builder.h"

namespace bvhlab::trav {

namespace {
#ifndef BVHLAB_NO_CUDA_REASON
#define BVHLAB_NO_CUDA_REASON "it was built without CUDA"
#endif
const char* const kNoCuda = "this bvhlab was built without CUDA: " BVHLAB_NO_CUDA_REASON;
}  // namespace

bool gpu_available(std::string* why) {
    if (why) *why = kNoCuda;
    return false;
}
int gpu_count() { return 0; }
std::string gpu_description() { return "none"; }
std::string gpu_driver() { return "none"; }
SmClock gpu_sm_clock() { return {}; }
int gpu_sm_count() { throw Error(kNoCuda); }
GpuMemoryUse gpu_memory_use() { return {}; }

namespace detail {
void* device_malloc(size_t) { throw Error(kNoCuda); }
void device_free(void*, size_t) noexcept {}
void copy_to_device(void*, const void*, size_t) { throw Error(kNoCuda); }
void copy_to_host(void*, const void*, size_t) { throw Error(kNoCuda); }
void fill_device_bytes(void*, uint8_t, size_t, void*) { throw Error(kNoCuda); }
GpuBuild gpu_build(const scene::TriangleMesh&, accel::BuilderKind, const accel::BuilderOptions&, bool) {
    throw Error(kNoCuda);
}
double gpu_refit(const RefitInput&) { throw Error(kNoCuda); }
GpuBuild gpu_build_tlas(uint32_t, const TlasInput&, accel::BuilderKind, const accel::BuilderOptions&) {
    throw Error(kNoCuda);
}
}  // namespace detail

DeviceTimer::DeviceTimer() { throw Error(kNoCuda); }
DeviceTimer::~DeviceTimer() = default;
void DeviceTimer::start(void*) { throw Error(kNoCuda); }
float DeviceTimer::stop(void*) { throw Error(kNoCuda); }

}  // namespace bvhlab::trav
