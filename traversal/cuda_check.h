// SPDX-License-Identifier: MIT
// CUDA error checks (tiny-cuda-nn style): evaluate once, check the returned code, throw
// bvhlab::CudaError with file:line, the expression and cudaGetErrorString.
#pragma once

#include <cuda_runtime_api.h>

#include <cstdio>
#include <string>

#include "accel/core/check.h"

namespace bvhlab {

class CudaError : public Error {
public:
    using Error::Error;
};

}  // namespace bvhlab

#define BVHLAB_CUDA_CHECK(expr)                                                                       \
    do {                                                                                              \
        const cudaError_t bvhlab_err_ = (expr);                                                       \
        if (bvhlab_err_ != cudaSuccess)                                                               \
            throw ::bvhlab::CudaError(std::string("CUDA error: ") + cudaGetErrorString(bvhlab_err_) + \
                                      " in '" #expr "' at " __FILE__ ":" + std::to_string(__LINE__)); \
    } while (0)

/// For destructors: logs and never throws.
#define BVHLAB_CUDA_CHECK_LOG(expr)                                                                                  \
    do {                                                                                                             \
        const cudaError_t bvhlab_err_ = (expr);                                                                      \
        if (bvhlab_err_ != cudaSuccess)                                                                              \
            std::fprintf(stderr, "bvhlab: CUDA error %s in '%s' at %s:%d\n", cudaGetErrorString(bvhlab_err_), #expr, \
                         __FILE__, __LINE__);                                                                        \
    } while (0)

/// After every launch; with BVHLAB_SYNC_AFTER_LAUNCH also synchronises to surface faults at once.
#if defined(BVHLAB_SYNC_AFTER_LAUNCH)
#define BVHLAB_CHECK_LAUNCH()                       \
    do {                                            \
        BVHLAB_CUDA_CHECK(cudaGetLastError());      \
        BVHLAB_CUDA_CHECK(cudaDeviceSynchronize()); \
    } while (0)
#else
#define BVHLAB_CHECK_LAUNCH() BVHLAB_CUDA_CHECK(cudaGetLastError())
#endif
