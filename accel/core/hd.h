// SPDX-License-Identifier: MIT
// Host/device annotations. The only file in bvhlab that tests __CUDACC__.
#pragma once

#if defined(__CUDACC__)
#define BVHLAB_UNROLL _Pragma("unroll")
#define BVHLAB_HD __host__ __device__
#define BVHLAB_DEVICE __device__
#define BVHLAB_FORCEINLINE __forceinline__
#else
#if defined(__clang__)
#define BVHLAB_UNROLL _Pragma("unroll")
#elif defined(__GNUC__)
#define BVHLAB_UNROLL _Pragma("GCC unroll 8")
#else
#define BVHLAB_UNROLL
#endif
#define BVHLAB_HD
#define BVHLAB_DEVICE
#if defined(__GNUC__) || defined(__clang__)
#define BVHLAB_FORCEINLINE inline __attribute__((always_inline))
#else
#define BVHLAB_FORCEINLINE inline
#endif
#endif

/// Debug-only check that also works in BVHLAB_HD code (assert on the device).
#if defined(NDEBUG)
#define BVHLAB_DCHECK(expr) ((void)0)
#else
#include <cassert>
#define BVHLAB_DCHECK(expr) assert(expr)
#endif
