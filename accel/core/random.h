// SPDX-License-Identifier: MIT
// Counter-based randomness: a hash of (seed, index) instead of a stateful generator, so
// parallel loops produce the same numbers in any order.
#pragma once

#include <cstdint>

#include "accel/core/hd.h"

namespace bvhlab {

/// SplitMix64 finaliser (Steele, Lea, Flood 2014): a well-mixed 64-bit hash of a counter.
BVHLAB_HD inline uint64_t splitmix64(uint64_t x) {
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

/// Uniform float in [0, 1) from the top 24 bits of a hash.
BVHLAB_HD inline float unit_float(uint64_t h) { return float(h >> 40) * (1.0f / 16777216.0f); }

}  // namespace bvhlab
