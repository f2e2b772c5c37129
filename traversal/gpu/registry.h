// SPDX-License-Identifier: MIT
// The kernel registry. Every GPU kernel is one .cu file under traversal/kernels/ that
// registers its name, the layout it traces, a one-line description, the stack it has and its
// launch function (BVHLAB_REGISTER_KERNEL). Nothing else names a kernel: the CLI, the
// benchmarks and the parameterised GPU tests iterate over the registry.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "traversal/device/bvh2_traverse.h"
#include "traversal/device/cwbvh_traverse.h"
#include "traversal/device/kd_traverse.h"
#include "traversal/device/two_level_traverse.h"
#include "traversal/gpu/ray_queue.h"
#include "traversal/structure.h"

namespace bvhlab::trav {

/// Everything a launch needs; the views that do not match the kernel's layout are null.
struct LaunchArgs {
    Bvh2View bvh2{};
    KdView kd{};
    CwbvhView cwbvh{};
    TwoLevelView two_level{};
    RayQueueView queue{};
    uint32_t capacity = 0;  ///< the queue's capacity: the grid covers it, threads read the count
    Query query = Query::kClosest;
    int kd_stack = 0;                ///< short-stack entries (kernels with short_stack)
    int block_size = 0;              ///< threads per block; 0 = the kernel's default
    uint32_t* d_next_ray = nullptr;  ///< a device counter zeroed before each launch (persistent kernels)
    uint32_t fetch_threshold = 0;    ///< idle lanes that trigger a dynamic fetch; 0 = the kernel's default
    void* stream = nullptr;          ///< cudaStream_t; null = the default stream
    /// Non-null: one entry per ray slot, where a kernel that counts (KernelInfo::counts) writes
    /// each ray's work; such a launch runs the counting instance of the kernel, not the timed one.
    TraversalCounters* counters = nullptr;
};

/// Idle lanes of a warp that start new rays in the dynamic-fetch kernels unless asked otherwise.
constexpr uint32_t kDefaultFetchThreshold = 8;

/// A kernel whose stack never overflows (it restarts instead).
constexpr uint32_t kNoStackLimit = UINT32_MAX;

struct KernelInfo {
    const char* name;                   ///< e.g. "speculative"
    Layout layout;                      ///< the layout it traces
    const char* description;            ///< one line
    uint32_t stack_entries;             ///< deepest tree (interior nodes) it traces, or kNoStackLimit
    bool short_stack;                   ///< takes a short-stack size (--kd-stack 1..8)
    int default_block;                  ///< threads per block unless asked otherwise
    void (*launch)(const LaunchArgs&);  ///< asynchronous on args.stream; throws CudaError
    int max_block = 1024;               ///< the largest block it launches (its __launch_bounds__)
    bool dynamic_fetch = false;         ///< takes a fetch threshold (--fetch-threshold 1..32)
    bool counts = false;                ///< runs a shared traversal and can count its work (LaunchArgs::counters)
    /// The kernel a structure of its layout gets unless one is named: one per layout, and for
    /// kd-trees one with a full stack and one with a short stack. Chosen by measurement
    /// (experiments/NOTES.md); the factory and the CLI ask the registry, never a name.
    bool is_default = false;
};

/// Adds a kernel; throws bvhlab::Error on a duplicate name. Returns true (for static init).
bool register_kernel(const KernelInfo& k);
/// Every registered kernel, BVH2 kernels first, each layout's in name order. Empty in a
/// build without CUDA.
std::vector<KernelInfo> registered_kernels();
/// The kernel of that name; throws bvhlab::Error listing the registered names otherwise.
const KernelInfo& find_kernel(const std::string& name);
/// The default kernel (KernelInfo::is_default) of `layout`; for kd-trees the one with a short
/// stack when `short_stack`. Throws bvhlab::Error when there is none (a build without CUDA).
const KernelInfo& default_kernel(Layout layout, bool short_stack = false);

}  // namespace bvhlab::trav

#define BVHLAB_REGISTER_KERNEL_CAT2(a, b) a##b
#define BVHLAB_REGISTER_KERNEL_CAT(a, b) BVHLAB_REGISTER_KERNEL_CAT2(a, b)
/// At namespace scope in a kernel's .cu file: BVHLAB_REGISTER_KERNEL({"name", Layout::kBvh2, ...});
#define BVHLAB_REGISTER_KERNEL(...)                                              \
    static const bool BVHLAB_REGISTER_KERNEL_CAT(bvhlab_registered_, __LINE__) = \
        ::bvhlab::trav::register_kernel(::bvhlab::trav::KernelInfo __VA_ARGS__)
