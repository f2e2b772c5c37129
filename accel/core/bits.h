// SPDX-License-Identifier: MIT
// Bit operations written once for host and device: one instruction each on both.
#pragma once

#include <cstdint>
#include <cstring>

#include "accel/core/hd.h"

namespace bvhlab {

/// Set bits of x.
BVHLAB_HD BVHLAB_FORCEINLINE uint32_t popc32(uint32_t x) {
#if defined(__CUDA_ARCH__)
    return uint32_t(__popc(x));
#else
    return uint32_t(__builtin_popcount(x));
#endif
}

/// Index of the highest set bit; x must not be 0.
BVHLAB_HD BVHLAB_FORCEINLINE uint32_t highest_bit(uint32_t x) {
#if defined(__CUDA_ARCH__)
    return 31u - uint32_t(__clz(x));
#else
    return 31u - uint32_t(__builtin_clz(x));
#endif
}

/// Index of the lowest set bit; x must not be 0.
BVHLAB_HD BVHLAB_FORCEINLINE uint32_t lowest_bit(uint32_t x) {
#if defined(__CUDA_ARCH__)
    return uint32_t(__ffs(x)) - 1u;
#else
    return uint32_t(__builtin_ctz(x));
#endif
}

/// The float with these bits.
BVHLAB_HD BVHLAB_FORCEINLINE float float_from_bits(uint32_t bits) {
#if defined(__CUDA_ARCH__)
    return __uint_as_float(bits);
#else
    float f;
    std::memcpy(&f, &bits, sizeof f);
    return f;
#endif
}

}  // namespace bvhlab
