// SPDX-License-Identifier: MIT
// Launchers of the BVH2 trace kernels, for traversal/launch.cu.
#pragma once

#include <cuda_runtime_api.h>

#include "accel/layouts/bvh2_node.h"
#include "traversal/device/ray.h"

namespace bvhlab::trav {

/// One thread per ray, the shared stack traversal (traverse_bvh2). Asynchronous on `stream`.
void launch_trace_bvh2(const accel::Bvh2Node* d_nodes, const accel::WoopTriangle* d_tris,
                       const uint32_t* d_tri_ids, const Ray* d_rays, Hit* d_hits, uint32_t count,
                       Query query, cudaStream_t stream);

}  // namespace bvhlab::trav
