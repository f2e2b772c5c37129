// SPDX-License-Identifier: MIT
// Denoising with Intel Open Image Denoise, found at run time: OIDN is not a Debian package, and
// the `pyoidn` wheel on PyPI ships the library (with its CPU and CUDA devices). Its C API is
// loaded with dlopen, so bvhlab builds and runs without it; only denoising needs it.
#pragma once

#include <string>

#include "renderer/image.h"

namespace bvhlab::render {

struct DenoiseOptions {
    /// libOpenImageDenoise.so, or a folder holding it; "" searches: $BVHLAB_OIDN, then an
    /// installed pyoidn wheel (pip's site-packages and user folders), then the system's library.
    std::string library;
    std::string device = "auto";  ///< auto (CUDA when OIDN can use it, else the CPU), cpu or cuda
};

struct DenoiseResult {
    Image image;
    std::string library;  ///< the OIDN library used
    std::string device;   ///< cpu or cuda
    double ms = 0.0;      ///< the three filters (albedo and normal prefiltered, then the beauty)
};

/// The OIDN library that `opts` names or the search finds, or "" with the reason in `why`
/// (which says how to install it).
std::string find_oidn(const DenoiseOptions& opts, std::string* why);

/// OIDN's RT filter on an HDR beauty image with its albedo and normal AOVs (the first hits'),
/// each AOV prefiltered first as OIDN recommends (cleanAux). Throws bvhlab::Error when OIDN is
/// missing or fails, naming the reason.
DenoiseResult denoise(const Image& beauty, const Image& albedo, const Image& normal, const DenoiseOptions& opts);

}  // namespace bvhlab::render
