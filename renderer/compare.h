// SPDX-License-Identifier: MIT
// Statistical comparison of two renders of the same scene (CPU against GPU, one estimator
// against another): are their means equal within the noise each reports?
#pragma once

#include <string>

#include "renderer/wavefront.h"

namespace bvhlab::render {

struct CompareConfig {
    uint32_t region = 8;           ///< square regions of this many pixels a side
    double region_z = 5.0;         ///< largest |z| a region's mean may have
    double pixel_z = 4.0;          ///< a pixel beyond this |z| is an outlier ...
    double pixel_outliers = 0.01;  ///< ... and at most this fraction of pixels may be
};

struct Comparison {
    double max_region_z = 0.0;  ///< over regions and channels
    uint32_t worst_region_x = 0, worst_region_y = 0;
    double pixel_outlier_fraction = 0.0;
    bool agree = true;
    std::string summary() const;
};

/// Compares the per-channel means of `a` and `b` (equal sizes, each with variance_of_mean),
/// per region (z of the difference of the regions' means, with the variances summed) and per
/// pixel (the fraction of outliers). Pixels where both variances are 0 must match to 1e-5
/// relative. Throws bvhlab::Error for different sizes.
Comparison compare_renders(const RenderResult& a, const RenderResult& b, const CompareConfig& cfg = {});

}  // namespace bvhlab::render
