// SPDX-License-Identifier: MIT
// What every trace kernel shares: 16-byte ray loads and hit stores, the one-thread-per-ray
// launch and the persistent-threads wrapper (Aila & Laine 2009, section 4), each around any
// per-ray functor `Hit f(const Ray&)`. A kernel file only picks a functor and registers it.
#pragma once

#include <cuda_runtime.h>

#include <algorithm>
#include <type_traits>

#include "traversal/cuda_check.h"
#include "traversal/gpu/device_buffer.h"
#include "traversal/gpu/registry.h"

namespace bvhlab::trav {

/// A 32-byte ray as two 16-byte loads through the read-only path.
__device__ __forceinline__ Ray load_ray(const Ray* rays, uint32_t i) {
    const float4* p = reinterpret_cast<const float4*>(rays + i);
    const float4 a = __ldg(p), b = __ldg(p + 1);
    return {{a.x, a.y, a.z}, a.w, {b.x, b.y, b.z}, b.w};
}

/// A 16-byte hit as one 16-byte store.
__device__ __forceinline__ void store_hit(Hit* hits, uint32_t i, const Hit& h) {
    reinterpret_cast<float4*>(hits)[i] = make_float4(__int_as_float(h.tri), h.t, h.u, h.v);
}

/// One thread per ray; threads past the device-side count return at once.
template <class PerRay>
__global__ void per_ray_kernel(RayQueueView q, PerRay f) {
    const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= __ldg(q.count)) return;
    store_hit(q.hits, i, f(load_ray(q.rays, i)));
}

/// Persistent threads with dynamic ray fetch: a grid that just fills the GPU, where each warp
/// takes the next 32 rays from a global counter with one atomic, traces them, and comes back
/// until the queue is empty. Warps that drew short rays fetch again early instead of idling
/// until the slowest warp of a block finishes, and no block is left for a last, partial wave.
template <class PerRay>
__global__ void persistent_kernel(RayQueueView q, uint32_t* next_ray, PerRay f) {
    const uint32_t count = __ldg(q.count);
    const uint32_t lane = threadIdx.x & 31u;
    while (true) {
        uint32_t base = 0;
        if (lane == 0) base = atomicAdd(next_ray, 32u);
        base = __shfl_sync(0xffffffffu, base, 0);
        if (base >= count) return;
        const uint32_t i = base + lane;
        if (i < count) store_hit(q.hits, i, f(load_ray(q.rays, i)));
        __syncwarp();
    }
}

inline int block_of(const LaunchArgs& a, int default_block) { return a.block_size ? a.block_size : default_block; }

/// Dynamic shared memory for `block` threads of `smem_per_thread` bytes each; raises the
/// kernel's limit when that is over the default 48 KB.
template <class Kernel>
size_t shared_bytes(Kernel kernel, int block, uint32_t smem_per_thread) {
    const size_t bytes = size_t(block) * smem_per_thread;
    if (bytes > 48 * 1024)
        BVHLAB_CUDA_CHECK(cudaFuncSetAttribute(kernel, cudaFuncAttributeMaxDynamicSharedMemorySize, int(bytes)));
    return bytes;
}

/// One thread per ray. `smem_per_thread`: dynamic shared memory the functor uses per thread.
template <class PerRay>
void launch_per_ray(const LaunchArgs& a, int default_block, const PerRay& f, uint32_t smem_per_thread = 0) {
    const int block = block_of(a, default_block);
    const uint32_t grid = (a.capacity + uint32_t(block) - 1) / uint32_t(block);
    if (grid == 0) return;
    const size_t smem = shared_bytes(per_ray_kernel<PerRay>, block, smem_per_thread);
    per_ray_kernel<<<grid, block, smem, static_cast<cudaStream_t>(a.stream)>>>(a.queue, f);
    BVHLAB_CHECK_LAUNCH();
}

template <class PerRay>
void launch_persistent(const LaunchArgs& a, int default_block, const PerRay& f) {
    const int block = block_of(a, default_block);
    int per_sm = 0;
    BVHLAB_CUDA_CHECK(cudaOccupancyMaxActiveBlocksPerMultiprocessor(&per_sm, persistent_kernel<PerRay>, block, 0));
    static const int sms = gpu_sm_count();
    const uint64_t needed = (uint64_t(a.capacity) + uint64_t(block) - 1) / uint64_t(block);
    const uint32_t grid = uint32_t(std::min<uint64_t>(needed, uint64_t(per_sm > 0 ? per_sm : 1) * uint64_t(sms)));
    if (grid == 0) return;
    persistent_kernel<<<grid, block, 0, static_cast<cudaStream_t>(a.stream)>>>(a.queue, a.d_next_ray, f);
    BVHLAB_CHECK_LAUNCH();
}

/// Calls `launch(std::true_type{})` for any-hit queries and `launch(std::false_type{})` for
/// closest-hit ones, so a kernel file instantiates both forms from one line.
template <class Launch>
void for_query(const LaunchArgs& a, Launch&& launch) {
    if (a.query == Query::kAny) launch(std::true_type{});
    else launch(std::false_type{});
}

}  // namespace bvhlab::trav
