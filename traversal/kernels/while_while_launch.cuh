// SPDX-License-Identifier: MIT
// The launch of every while-while kernel: the build-time choices of trace_while_while, one
// thread per ray or persistent threads. A while-while kernel file is then one registration.
#pragma once

#include "traversal/device/bvh2_while_while.cuh"
#include "traversal/kernels/launch_helpers.cuh"

namespace bvhlab::trav {

template <bool kSpeculative, bool kFmaSlabs, bool kPersistent, bool kSharedStack = false>
void launch_while_while(const LaunchArgs& a) {
    constexpr int kBlock = 128;  // 64 and 256 were within 2% (experiments/NOTES.md)
    constexpr uint32_t kSmem = kSharedStack ? ww_detail::kSharedStackBytes : 0;
    static_assert(!(kPersistent && kSharedStack), "the persistent launch takes no shared memory");
    for_query(a, [&](auto any) {
        const WhileWhileTrace<decltype(any)::value, kSpeculative, kFmaSlabs, kSharedStack> f{a.bvh2};
        if constexpr (kPersistent) launch_persistent(a, kBlock, f);
        else launch_per_ray(a, kBlock, f, kSmem);
    });
}

}  // namespace bvhlab::trav
