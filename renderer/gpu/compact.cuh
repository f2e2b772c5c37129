// SPDX-License-Identifier: MIT
// Stage "compact", fused into the shade kernel: a CUB BlockScan numbers each block's live
// paths and shadow rays, one atomicAdd per block and queue reserves their places, and every
// thread writes its results there. It replaced CUB DeviceSelect::Flagged plus a gather kernel
// per queue, which ran over the whole capacity at every bounce (~25% of a Cornell box render,
// NOTES.md session 15). Queue order between blocks follows the atomics; a path's result depends
// only on its slot, so the image does not.
#pragma once

#include <cub/block/block_scan.cuh>

#include <cstdint>

namespace bvhlab::render::gpu {

/// Positions in two output queues for this thread's two flags (each block holds at most 65535
/// threads, so both counts share one 32-bit scan). Every thread of the block must call it.
template <int kBlock>
struct BlockCompactor {
    using Scan = cub::BlockScan<uint32_t, kBlock>;
    struct Storage {
        typename Scan::TempStorage scan;
        uint32_t base[2];
    };
    static_assert(kBlock < 65536, "two 16-bit counts share one scan");

    /// Sets pos_a / pos_b to this thread's places in queues a and b (valid where flag_a /
    /// flag_b), reserving the block's totals with *count_a / *count_b.
    __device__ static void places(Storage& st, bool flag_a, bool flag_b, uint32_t* count_a, uint32_t* count_b,
                                  uint32_t& pos_a, uint32_t& pos_b) {
        const uint32_t flags = uint32_t(flag_a) | (uint32_t(flag_b) << 16);
        uint32_t offset, total;
        Scan(st.scan).ExclusiveSum(flags, offset, total);
        if (threadIdx.x == 0) {
            st.base[0] = (total & 0xFFFFu) ? atomicAdd(count_a, total & 0xFFFFu) : 0u;
            st.base[1] = (total >> 16) ? atomicAdd(count_b, total >> 16) : 0u;
        }
        __syncthreads();
        pos_a = st.base[0] + (offset & 0xFFFFu);
        pos_b = st.base[1] + (offset >> 16);
    }
};

}  // namespace bvhlab::render::gpu
