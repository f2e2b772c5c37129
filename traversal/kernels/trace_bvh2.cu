// SPDX-License-Identifier: MIT
// Plain GPU kernels over the shared BVH2 traversal: one thread per ray. The baseline that
// the Aila-Laine style kernels (while-while, persistent threads) will be measured against.
#include "traversal/cuda_check.h"
#include "traversal/device/bvh2_traverse.h"
#include "traversal/kernels/trace_bvh2.h"

namespace bvhlab::trav {
namespace {

template <bool kAnyHit>
__global__ void trace_bvh2_kernel(const accel::Bvh2Node* __restrict__ nodes,
                                  const accel::WoopTriangle* __restrict__ tris,
                                  const uint32_t* __restrict__ tri_ids, const Ray* __restrict__ rays,
                                  Hit* __restrict__ hits, uint32_t count) {
    const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= count) return;
    hits[i] = traverse_bvh2<kAnyHit>(nodes, tris, tri_ids, rays[i]);
}

}  // namespace

void launch_trace_bvh2(const accel::Bvh2Node* d_nodes, const accel::WoopTriangle* d_tris,
                       const uint32_t* d_tri_ids, const Ray* d_rays, Hit* d_hits, uint32_t count,
                       Query query, cudaStream_t stream) {
    if (count == 0) return;
    constexpr uint32_t kBlock = 128;
    const uint32_t grid = (count + kBlock - 1) / kBlock;
    if (query == Query::kAny) {
        trace_bvh2_kernel<true><<<grid, kBlock, 0, stream>>>(d_nodes, d_tris, d_tri_ids, d_rays, d_hits, count);
    } else {
        trace_bvh2_kernel<false><<<grid, kBlock, 0, stream>>>(d_nodes, d_tris, d_tri_ids, d_rays, d_hits, count);
    }
    BVHLAB_CHECK_LAUNCH();
}

}  // namespace bvhlab::trav
