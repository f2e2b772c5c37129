// SPDX-License-Identifier: MIT
// Minimal float3 for code shared by host and device. Host-only math (cameras, loaders) uses GLM.
#pragma once

#include <cmath>

#include "accel/core/hd.h"

namespace bvhlab {

/// Three packed floats (12 bytes), usable in host and device code.
struct Vec3 {
    float x, y, z;

    BVHLAB_HD float operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
    BVHLAB_HD float& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
};
static_assert(sizeof(Vec3) == 12, "Vec3 must be three packed floats");

/// min/max as compare-and-select. Unlike fminf/fmaxf these have no NaN rules, so host
/// compilers inline them as minss/maxss instead of calling libm (30% of build time when not).
/// With a NaN operand they return the second argument on the host. On the device they are
/// fminf/fmaxf, one FMNMX each: the compare-select took an FSETP and an FSEL, 24 instructions
/// of ~98 per BVH2 node visit (experiments/NOTES.md, session 12). The two differ only for a
/// NaN operand, which no traversal produces (slab distances stay numbers, see slab_entry).
BVHLAB_HD BVHLAB_FORCEINLINE float min_f(float a, float b) {
#if defined(__CUDA_ARCH__)
    return fminf(a, b);
#else
    return a < b ? a : b;
#endif
}
BVHLAB_HD BVHLAB_FORCEINLINE float max_f(float a, float b) {
#if defined(__CUDA_ARCH__)
    return fmaxf(a, b);
#else
    return a > b ? a : b;
#endif
}

BVHLAB_HD inline Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
BVHLAB_HD inline Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
BVHLAB_HD inline Vec3 operator*(Vec3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
BVHLAB_HD inline Vec3 operator*(float s, Vec3 a) { return a * s; }
BVHLAB_HD inline Vec3 operator*(Vec3 a, Vec3 b) { return {a.x * b.x, a.y * b.y, a.z * b.z}; }
BVHLAB_HD inline float dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
BVHLAB_HD inline Vec3 cross(Vec3 a, Vec3 b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
BVHLAB_HD inline float length(Vec3 a) { return sqrtf(dot(a, a)); }
BVHLAB_HD inline Vec3 vmin(Vec3 a, Vec3 b) { return {min_f(a.x, b.x), min_f(a.y, b.y), min_f(a.z, b.z)}; }
BVHLAB_HD inline Vec3 vmax(Vec3 a, Vec3 b) { return {max_f(a.x, b.x), max_f(a.y, b.y), max_f(a.z, b.z)}; }

}  // namespace bvhlab
