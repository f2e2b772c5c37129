// SPDX-License-Identifier: MIT
// The launch shape every stage kernel shares.
#pragma once

#include <cuda_runtime.h>

#include "traversal/cuda_check.h"

namespace bvhlab::render::gpu {

constexpr int kStageBlock = 256;

inline unsigned stage_blocks(uint32_t n) { return (n + kStageBlock - 1) / kStageBlock; }
inline cudaStream_t as_stream(void* s) { return static_cast<cudaStream_t>(s); }

}  // namespace bvhlab::render::gpu
