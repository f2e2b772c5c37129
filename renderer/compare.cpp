// SPDX-License-Identifier: MIT
#include "renderer/compare.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "accel/core/check.h"

namespace bvhlab::render {

std::string Comparison::summary() const {
    char buf[200];
    std::snprintf(buf, sizeof buf, "%s: worst region |z| %.2f at (%u, %u), %.3f%% pixel outliers",
                  agree ? "agree" : "DIFFER", max_region_z, worst_region_x, worst_region_y,
                  100.0 * pixel_outlier_fraction);
    return buf;
}

Comparison compare_renders(const RenderResult& a, const RenderResult& b, const CompareConfig& cfg) {
    BVHLAB_CHECK(a.mean.width == b.mean.width && a.mean.height == b.mean.height,
                 "cannot compare renders of different sizes");
    BVHLAB_CHECK(cfg.region >= 1, "the comparison region must be at least one pixel");
    const uint32_t w = a.mean.width, h = a.mean.height;
    Comparison c;
    size_t outliers = 0;
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x) {
            const Vec3 d = a.mean.at(x, y) - b.mean.at(x, y);
            const Vec3 v = a.variance_of_mean.at(x, y) + b.variance_of_mean.at(x, y);
            bool out = false;
            for (int ch = 0; ch < 3; ++ch) {
                if (v[ch] > 0.0f) {
                    out = out || std::fabs(d[ch]) > cfg.pixel_z * std::sqrt(v[ch]);
                } else {
                    const float scale = std::max(std::fabs(a.mean.at(x, y)[ch]), 1e-6f);
                    out = out || std::fabs(d[ch]) > 1e-5f * scale;
                }
            }
            outliers += out;
        }
    c.pixel_outlier_fraction = double(outliers) / double(size_t(w) * h);
    for (uint32_t ry = 0; ry < h; ry += cfg.region)
        for (uint32_t rx = 0; rx < w; rx += cfg.region) {
            double sd[3] = {0, 0, 0}, sv[3] = {0, 0, 0};
            size_t n = 0;
            for (uint32_t y = ry; y < std::min(h, ry + cfg.region); ++y)
                for (uint32_t x = rx; x < std::min(w, rx + cfg.region); ++x, ++n)
                    for (int ch = 0; ch < 3; ++ch) {
                        sd[ch] += double(a.mean.at(x, y)[ch]) - double(b.mean.at(x, y)[ch]);
                        sv[ch] += double(a.variance_of_mean.at(x, y)[ch]) + double(b.variance_of_mean.at(x, y)[ch]);
                    }
            for (int ch = 0; ch < 3; ++ch) {
                // The region's mean difference over its standard deviation (n^2 cancels).
                double z = sv[ch] > 0.0 ? std::fabs(sd[ch]) / std::sqrt(sv[ch])
                                        : (std::fabs(sd[ch]) > 1e-5 * double(n) ? INFINITY : 0.0);
                if (z > c.max_region_z) {
                    c.max_region_z = z;
                    c.worst_region_x = rx;
                    c.worst_region_y = ry;
                }
            }
        }
    c.agree = c.max_region_z <= cfg.region_z && c.pixel_outlier_fraction <= cfg.pixel_outliers;
    return c;
}

}  // namespace bvhlab::render
