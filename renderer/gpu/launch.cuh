// SPDX-License-Identifier: MIT
// The launch shape every stage kernel shares.
#pragma once

#include <cuda_runtime.h>

#include "renderer/gpu/stage_kernels.h"
#include "traversal/cuda_check.h"

namespace bvhlab::render::gpu {

constexpr int kStageBlock = 256;

inline unsigned stage_blocks(uint32_t n) { return (n + kStageBlock - 1) / kStageBlock; }
inline cudaStream_t as_stream(void* s) { return static_cast<cudaStream_t>(s); }

/// The chores of a stage kernel (stage_kernels.h), by its grid's first thread. Call before
/// any early return.
__device__ inline void do_chores(const Chores& c) {
    if (blockIdx.x != 0 || threadIdx.x != 0) return;
    for (int k = 0; k < 2; ++k) {
        if (c.total[k] && c.count[k]) *c.total[k] += *c.count[k];
        if (c.zero[k]) *c.zero[k] = 0;
    }
    for (uint32_t k = 0; k < c.zero_run_n; ++k) c.zero_run[k] = 0;
}

}  // namespace bvhlab::render::gpu
