// SPDX-License-Identifier: MIT
// The launch of every while-while kernel, single-level and two-level: the build-time choices of
// the traversal, one thread per ray or persistent threads. A while-while kernel file is then one
// registration.
#pragma once

#include "traversal/device/bvh2_while_while.cuh"
#include "traversal/device/two_level_while_while.cuh"
#include "traversal/kernels/launch_helpers.cuh"

namespace bvhlab::trav {

/// How a while-while kernel hands out rays.
enum class Fetch { kPerRay, kPersistent, kDynamic };

/// kMinBlocks > 0: a one-thread-per-ray launch with __launch_bounds__(128, kMinBlocks).
template <bool kSpeculative, bool kFmaSlabs, Fetch kFetch, bool kSharedStack = false, int kMinBlocks = 0>
void launch_while_while(const LaunchArgs& a) {
    constexpr int kBlock = 128;  // 64 and 256 were within 2% (experiments/NOTES.md)
    constexpr uint32_t kSmem = kSharedStack ? ww_detail::kSharedStackBytes : 0;
    static_assert(kFetch == Fetch::kPerRay || !kSharedStack, "only the per-ray launch takes shared memory");
    for_query(a, [&](auto any) {
        const WhileWhileTrace<decltype(any)::value, kSpeculative, kFmaSlabs, kSharedStack> f{a.bvh2};
        if constexpr (kFetch == Fetch::kPersistent)
            launch_persistent(a, kBlock, f);
        else if constexpr (kFetch == Fetch::kDynamic)
            launch_dynamic_fetch(a, kBlock, f, a.fetch_threshold ? a.fetch_threshold : kDefaultFetchThreshold);
        else if constexpr (kMinBlocks > 0)
            launch_per_ray<kBlock, kMinBlocks>(a, kBlock, f, kSmem);
        else
            launch_per_ray(a, kBlock, f, kSmem);
    });
}

/// The two-level forms (two_level_while_while.cuh): FMA slabs, one thread per ray or dynamic
/// fetch.
template <bool kSpeculative, Fetch kFetch>
void launch_two_level_while_while(const LaunchArgs& a) {
    constexpr int kBlock = 128;
    static_assert(kFetch != Fetch::kPersistent, "no persistent form without dynamic fetch");
    for_query(a, [&](auto any) {
        const TwoLevelWhileWhileTrace<decltype(any)::value, kSpeculative, true> f{a.two_level};
        if constexpr (kFetch == Fetch::kDynamic)
            launch_dynamic_fetch(a, kBlock, f, a.fetch_threshold ? a.fetch_threshold : kDefaultFetchThreshold);
        else
            launch_per_ray(a, kBlock, f);
    });
}

}  // namespace bvhlab::trav
