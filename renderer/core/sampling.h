// SPDX-License-Identifier: MIT
// Random numbers and warps shared by the CPU and GPU integrators. Numbers are counter-based: a
// path's dimension d at pixel p and sample s is a pure function of (p, s, d, seed), so any
// stage on either device draws the same number without carrying generator state, and the CPU
// and GPU renders of one seed trace the same paths up to floating-point differences.
#pragma once

#include <cstdint>

#include "accel/core/hd.h"
#include "accel/core/vec3.h"

namespace bvhlab::render {

constexpr float kPi = 3.14159265358979323846f;
constexpr float kInvPi = 0.31830988618379067154f;

/// PCG's output permutation as a 32-bit hash (Jarzynski & Olano, "Hash functions for GPU
/// rendering", JCGT 2020: the best quality per cost of the hashes they measured).
BVHLAB_HD inline uint32_t pcg_hash(uint32_t v) {
    const uint32_t state = v * 747796405u + 2891336453u;
    const uint32_t word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

/// Uniform in [0, 1): dimension `dim` of sample `sample` of pixel `pixel`.
BVHLAB_HD inline float rand01(uint32_t pixel, uint32_t sample, uint32_t dim, uint32_t seed) {
    const uint32_t h = pcg_hash(pixel ^ pcg_hash(sample ^ pcg_hash(dim ^ pcg_hash(seed))));
    return float(h >> 8) * (1.0f / 16777216.0f);
}

/// Dimensions of one path: the camera's first, then a fixed block per bounce.
enum Dim : uint32_t {
    kDimPixelX = 0,
    kDimPixelY,
    kDimLensU,
    kDimLensV,
    kDimTime,
    kDimCameraEnd,
    // per bounce, at kDimCameraEnd + bounce * kDimsPerBounce:
    kDimLightPick = 0,  ///< which light (emissive triangles or the sky)
    kDimLight0,         ///< the light's point or direction
    kDimLight1,
    kDimLight2,
    kDimBsdfLobe,  ///< lobe choice (glass, plastic)
    kDimBsdf0,     ///< the BSDF's direction
    kDimBsdf1,
    kDimRoulette,
    kDimsPerBounce
};

BVHLAB_HD inline uint32_t bounce_dim(uint32_t bounce, uint32_t d) {
    return kDimCameraEnd + bounce * kDimsPerBounce + d;
}

BVHLAB_HD inline Vec3 normalize(Vec3 v) { return v * (1.0f / sqrtf(dot(v, v))); }
BVHLAB_HD inline float max3(Vec3 v) { return max_f(v.x, max_f(v.y, v.z)); }
BVHLAB_HD inline float luminance(Vec3 c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }
BVHLAB_HD inline Vec3 splat(float s) { return {s, s, s}; }

/// Orthonormal basis around unit `n` (Duff et al., "Building an orthonormal basis, revisited",
/// JCGT 2017): no division by a small number for any n.
struct Frame {
    Vec3 t, b, n;

    BVHLAB_HD static Frame around(Vec3 n) {
        const float sign = n.z >= 0.0f ? 1.0f : -1.0f;
        const float a = -1.0f / (sign + n.z);
        const float b = n.x * n.y * a;
        return {{1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x}, {b, sign + n.y * n.y * a, -n.y}, n};
    }
    BVHLAB_HD Vec3 to_local(Vec3 v) const { return {dot(v, t), dot(v, b), dot(v, n)}; }
    BVHLAB_HD Vec3 to_world(Vec3 v) const { return t * v.x + b * v.y + n * v.z; }
};

/// Concentric map of the unit square to the unit disk (Shirley & Chiu 1997).
BVHLAB_HD inline void sample_disk(float u0, float u1, float& x, float& y) {
    const float a = 2.0f * u0 - 1.0f, b = 2.0f * u1 - 1.0f;
    if (a == 0.0f && b == 0.0f) {
        x = y = 0.0f;
        return;
    }
    float r, phi;
    if (a * a > b * b) {
        r = a;
        phi = (kPi / 4.0f) * (b / a);
    } else {
        r = b;
        phi = (kPi / 2.0f) - (kPi / 4.0f) * (a / b);
    }
    x = r * cosf(phi);
    y = r * sinf(phi);
}

/// Cosine-weighted direction around +z (Malley's method); pdf = z / pi.
BVHLAB_HD inline Vec3 sample_cosine_hemisphere(float u0, float u1) {
    float x, y;
    sample_disk(u0, u1, x, y);
    return {x, y, sqrtf(max_f(0.0f, 1.0f - x * x - y * y))};
}

/// Uniform direction on the unit sphere; pdf = 1 / (4 pi).
BVHLAB_HD inline Vec3 sample_uniform_sphere(float u0, float u1) {
    const float z = 1.0f - 2.0f * u0;
    const float r = sqrtf(max_f(0.0f, 1.0f - z * z));
    const float phi = 2.0f * kPi * u1;
    return {r * cosf(phi), r * sinf(phi), z};
}

/// Uniform barycentrics (b1, b2) on a triangle (the square-root warp).
BVHLAB_HD inline void sample_triangle(float u0, float u1, float& b1, float& b2) {
    const float s = sqrtf(u0);
    b1 = 1.0f - s;
    b2 = u1 * s;
}

/// Veach's power heuristic (beta = 2) for two strategies with one sample each.
BVHLAB_HD inline float power_heuristic(float pdf_a, float pdf_b) {
    const float a = pdf_a * pdf_a, b = pdf_b * pdf_b;
    return a + b > 0.0f ? a / (a + b) : 0.0f;
}

}  // namespace bvhlab::render
