// SPDX-License-Identifier: MIT
// What every trace kernel shares: 16-byte ray loads and hit stores (traversal/device/ray.h), the one-thread-per-ray
// launch and the persistent-threads wrapper (Aila & Laine 2009, section 4), each around any
// per-ray functor `Hit f(const Ray&)`. A kernel file only picks a functor and registers it.
#pragma once

#include <cuda_runtime.h>

#include <algorithm>
#include <type_traits>

#include "accel/core/check.h"
#include "traversal/cuda_check.h"
#include "traversal/gpu/device_buffer.h"
#include "traversal/gpu/registry.h"

namespace bvhlab::trav {

/// One thread per ray; threads past the device-side count return at once.
template <class PerRay>
__device__ __forceinline__ void trace_one_per_thread(const RayQueueView& q, const PerRay& f) {
    const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= __ldg(q.count)) return;
    store_hit(q.hits, i, f(load_ray(q.rays, i)));
}

/// The one-thread-per-ray kernel with no launch bounds. (__launch_bounds__(1024, 1), which
/// caps nothing at 64 registers, still made nvcc take 62 registers instead of 56 for
/// while-while-fma.)
template <class PerRay>
__global__ void per_ray_kernel(RayQueueView q, PerRay f) {
    trace_one_per_thread(q, f);
}

/// The same held to __launch_bounds__(kMaxThreads, kMinBlocks): with (128, 10) the compiler
/// keeps to 48 registers, so that 10 blocks of 128 fit on an SM.
template <class PerRay, int kMaxThreads, int kMinBlocks>
__global__ void __launch_bounds__(kMaxThreads, kMinBlocks) per_ray_kernel_bounded(RayQueueView q, PerRay f) {
    trace_one_per_thread(q, f);
}

/// One thread per ray that also writes the ray's work: f(ray, &counters) runs a shared
/// traversal with its counters (the timed kernels call f(ray), which counts nothing).
template <class PerRay>
__global__ void per_ray_counted_kernel(RayQueueView q, TraversalCounters* counters, PerRay f) {
    const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= __ldg(q.count)) return;
    TraversalCounters c{};
    store_hit(q.hits, i, f(load_ray(q.rays, i), &c));
    counters[i] = c;
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

/// Persistent threads with dynamic ray fetch inside the warp (Aila & Laine 2009, section 4):
/// a lane whose ray has finished idles only until `threshold` lanes of its warp have; then the
/// idle lanes take that many new rays with one atomic and start them while the others go on.
/// Without it a warp waits for its slowest lane (on furball's diffuse rays 18% of lanes were
/// busy per issued instruction). `Trace` is resumable: State, Stack, start, step, done, result.
template <class Trace>
__device__ __forceinline__ void dynamic_fetch_loop(const RayQueueView& q, uint32_t* next_ray, const Trace& f,
                                                   uint32_t threshold) {
    const uint32_t count = __ldg(q.count);
    const uint32_t lane = threadIdx.x & 31u;
    typename Trace::State s;
    typename Trace::Stack stack;
    uint32_t ray = 0;
    bool alive = false, exhausted = false;
    while (true) {
        const uint32_t idle = __ballot_sync(0xffffffffu, !alive);
        const uint32_t want = uint32_t(__popc(idle));
        if (!exhausted && want >= threshold) {
            uint32_t base = 0;
            if (lane == 0) base = atomicAdd(next_ray, want);
            base = __shfl_sync(0xffffffffu, base, 0);
            if (!alive) {
                ray = base + uint32_t(__popc(idle & ((1u << lane) - 1u)));
                if (ray < count) {
                    f.start(s, stack, load_ray(q.rays, ray));
                    alive = true;
                }
            }
            exhausted = base + want >= count;  // the same in every lane
        }
        if (!__any_sync(0xffffffffu, alive)) return;
        if (alive) {
            f.step(s, stack);
            if (f.done(s)) {
                store_hit(q.hits, ray, f.result(s));
                alive = false;
            }
        }
    }
}

template <class Trace>
__global__ void dynamic_fetch_kernel(RayQueueView q, uint32_t* next_ray, Trace f, uint32_t threshold) {
    dynamic_fetch_loop(q, next_ray, f, threshold);
}

/// The same held to __launch_bounds__(kMaxThreads, kMinBlocks): (128, 8) keeps the compiler to
/// 64 registers, so that 8 blocks of 128 fit on an SM.
template <class Trace, int kMaxThreads, int kMinBlocks>
__global__ void __launch_bounds__(kMaxThreads, kMinBlocks)
    dynamic_fetch_kernel_bounded(RayQueueView q, uint32_t* next_ray, Trace f, uint32_t threshold) {
    dynamic_fetch_loop(q, next_ray, f, threshold);
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
/// kMinBlocks > 0 launches per_ray_kernel_bounded<kMaxThreads, kMinBlocks>.
template <int kMaxThreads = 1024, int kMinBlocks = 0, class PerRay>
void launch_per_ray(const LaunchArgs& a, int default_block, const PerRay& f, uint32_t smem_per_thread = 0) {
    const int block = block_of(a, default_block);
    const uint32_t grid = (a.capacity + uint32_t(block) - 1) / uint32_t(block);
    if (grid == 0) return;
    if (a.counters) {  // the counting instance (KernelInfo::counts), for tests and work figures
        if constexpr (std::is_invocable_v<const PerRay&, const Ray&, TraversalCounters*>) {
            per_ray_counted_kernel<PerRay>
                <<<grid, block, 0, static_cast<cudaStream_t>(a.stream)>>>(a.queue, a.counters, f);
            BVHLAB_CHECK_LAUNCH();
            return;
        } else {
            throw Error("this kernel does not count its work");
        }
    }
    auto launch = [&](auto* kernel) {
        const size_t smem = shared_bytes(kernel, block, smem_per_thread);
        kernel<<<grid, block, smem, static_cast<cudaStream_t>(a.stream)>>>(a.queue, f);
    };
    if constexpr (kMinBlocks > 0)
        launch(per_ray_kernel_bounded<PerRay, kMaxThreads, kMinBlocks>);
    else
        launch(per_ray_kernel<PerRay>);
    BVHLAB_CHECK_LAUNCH();
}

/// Blocks of a persistent grid: as many as fit on the GPU at once, and no more than the
/// queue's capacity needs.
template <class Kernel>
uint32_t persistent_grid(Kernel kernel, int block, uint32_t capacity) {
    int per_sm = 0;
    BVHLAB_CUDA_CHECK(cudaOccupancyMaxActiveBlocksPerMultiprocessor(&per_sm, kernel, block, 0));
    static const int sms = gpu_sm_count();
    const uint64_t needed = (uint64_t(capacity) + uint64_t(block) - 1) / uint64_t(block);
    return uint32_t(std::min<uint64_t>(needed, uint64_t(per_sm > 0 ? per_sm : 1) * uint64_t(sms)));
}

template <class PerRay>
void launch_persistent(const LaunchArgs& a, int default_block, const PerRay& f) {
    const int block = block_of(a, default_block);
    const uint32_t grid = persistent_grid(persistent_kernel<PerRay>, block, a.capacity);
    if (grid == 0) return;
    persistent_kernel<<<grid, block, 0, static_cast<cudaStream_t>(a.stream)>>>(a.queue, a.d_next_ray, f);
    BVHLAB_CHECK_LAUNCH();
}

/// kMinBlocks > 0 launches dynamic_fetch_kernel_bounded<kMaxThreads, kMinBlocks>.
template <int kMaxThreads = 1024, int kMinBlocks = 0, class Trace>
void launch_dynamic_fetch(const LaunchArgs& a, int default_block, const Trace& f, uint32_t threshold) {
    const int block = block_of(a, default_block);
    auto launch = [&](auto* kernel) {
        const uint32_t grid = persistent_grid(kernel, block, a.capacity);
        if (grid == 0) return;
        kernel<<<grid, block, 0, static_cast<cudaStream_t>(a.stream)>>>(a.queue, a.d_next_ray, f, threshold);
        BVHLAB_CHECK_LAUNCH();
    };
    if constexpr (kMinBlocks > 0)
        launch(dynamic_fetch_kernel_bounded<Trace, kMaxThreads, kMinBlocks>);
    else
        launch(dynamic_fetch_kernel<Trace>);
}

/// Calls `launch(std::true_type{})` for any-hit queries and `launch(std::false_type{})` for
/// closest-hit ones, so a kernel file instantiates both forms from one line.
template <class Launch>
void for_query(const LaunchArgs& a, Launch&& launch) {
    if (a.query == Query::kAny)
        launch(std::true_type{});
    else
        launch(std::false_type{});
}

/// Calls launch(any, vertex_tris) with the query and a CWBVH's triangle format as
/// std::bool_constant tags, so that each kernel is compiled for the format it reads.
template <typename Launch>
void for_cwbvh_query(const LaunchArgs& a, Launch&& launch) {
    for_query(a, [&](auto any) {
        if (a.cwbvh.vtris)
            launch(any, std::true_type{});
        else
            launch(any, std::false_type{});
    });
}

}  // namespace bvhlab::trav
