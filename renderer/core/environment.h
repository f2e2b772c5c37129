// SPDX-License-Identifier: MIT
// A lat-long (equirectangular) environment map and its importance sampling, host and device
// code written once. Directions map to the image as: u = 0.5 + atan2(d.x, -d.z) / (2 pi) across,
// v = acos(d.y) / pi down (+y is up; the image centre looks along -z). Sampling picks a pixel
// in proportion to its luminance times sin(theta) (the solid angle of its row) with a
// marginal CDF over rows and a conditional CDF per row (pbrt's Distribution2D), then a point
// uniformly within the pixel; pdf(d) = p(u, v) / (2 pi^2 sin(theta)).
#pragma once

#include <cstdint>

#include "renderer/core/sampling.h"

namespace bvhlab::render {

struct EnvView {
    const Vec3* pixels = nullptr;    ///< width x height, row-major, top row first (linear radiance x scale)
    const float* row_cdf = nullptr;  ///< height + 1 entries, 0 ... 1
    const float* col_cdf = nullptr;  ///< height rows of width + 1 entries, each 0 ... 1
    const float* row_pdf = nullptr;  ///< height entries: the row's probability x height
    const float* col_pdf = nullptr;  ///< height x width: the pixel's probability in its row x width
    uint32_t width = 0, height = 0;

    BVHLAB_HD bool present() const { return width > 0; }
};

/// The image coordinates (u, v) in [0, 1)^2 of unit direction d.
BVHLAB_HD inline void env_uv(Vec3 d, float& u, float& v) {
    u = 0.5f + atan2f(d.x, -d.z) * (0.5f * kInvPi);
    v = acosf(max_f(-1.0f, min_f(1.0f, d.y))) * kInvPi;
    u = u - floorf(u);
    v = min_f(v, 0.99999994f);
}

BVHLAB_HD inline Vec3 env_direction(float u, float v) {
    const float phi = (u - 0.5f) * 2.0f * kPi, theta = v * kPi;
    const float st = sinf(theta);
    return {st * sinf(phi), cosf(theta), -st * cosf(phi)};
}

BVHLAB_HD inline uint32_t env_index(const EnvView& e, float u, float v) {
    const uint32_t x = min_f(float(e.width - 1), u * float(e.width));
    const uint32_t y = min_f(float(e.height - 1), v * float(e.height));
    return y * e.width + x;
}

/// Radiance arriving from direction d (nearest pixel).
BVHLAB_HD inline Vec3 env_radiance(const EnvView& e, Vec3 d) {
    float u, v;
    env_uv(d, u, v);
    return e.pixels[env_index(e, u, v)];
}

/// Solid-angle density with which env_sample picks direction d.
BVHLAB_HD inline float env_pdf(const EnvView& e, Vec3 d) {
    float u, v;
    env_uv(d, u, v);
    const float st = sinf(v * kPi);
    if (st <= 0.0f) return 0.0f;
    const uint32_t i = env_index(e, u, v);
    const uint32_t y = i / e.width;
    return e.row_pdf[y] * e.col_pdf[i] / (2.0f * kPi * kPi * st);
}

/// The first index i in [0, n) with cdf[i + 1] > x (cdf has n + 1 entries, cdf[n] = 1).
BVHLAB_HD inline uint32_t cdf_find(const float* cdf, uint32_t n, float x) {
    uint32_t lo = 0, hi = n;  // cdf[lo] <= x < cdf[hi]
    while (hi - lo > 1) {
        const uint32_t mid = (lo + hi) / 2;
        if (cdf[mid] <= x)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

/// A direction by importance, with its solid-angle density.
BVHLAB_HD inline Vec3 env_sample(const EnvView& e, float u0, float u1, float& pdf) {
    const uint32_t y = cdf_find(e.row_cdf, e.height, u0);
    const float* row = e.col_cdf + size_t(y) * (e.width + 1);
    const uint32_t x = cdf_find(row, e.width, u1);
    // Uniform within the chosen pixel: the offsets reuse what is left of u0 and u1.
    const float dy = (u0 - e.row_cdf[y]) / max_f(e.row_cdf[y + 1] - e.row_cdf[y], 1e-30f);
    const float dx = (u1 - row[x]) / max_f(row[x + 1] - row[x], 1e-30f);
    const float u = (float(x) + min_f(dx, 0.99999f)) / float(e.width);
    const float v = (float(y) + min_f(dy, 0.99999f)) / float(e.height);
    const Vec3 d = env_direction(u, v);
    pdf = env_pdf(e, d);
    return d;
}

}  // namespace bvhlab::render
