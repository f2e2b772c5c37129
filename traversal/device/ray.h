// SPDX-License-Identifier: MIT
// Ray and hit records shared by the CPU tracer, the GPU kernels, the Embree oracle and the
// ray/hit files. Both are plain data whose bytes are the file records.
#pragma once

#include <cstdint>

#include "accel/core/hd.h"
#include "accel/core/vec3.h"

namespace bvhlab::trav {

/// A ray o + t d with t in (tmin, tmax), 32 bytes. The direction need not be normalised;
/// t is in units of |d|.
struct Ray {
    Vec3 org;    // 12 bytes
    float tmin;  // 4 bytes
    Vec3 dir;    // 12 bytes
    float tmax;  // 4 bytes: total 32 bytes
};
static_assert(sizeof(Ray) == 32, "Ray is a 32-byte file record");

/// Closest or any hit, 16 bytes. tri = -1 is a miss. The hit point is
/// (1 - u - v) v0 + u v1 + v v2 of triangle `tri` (Embree's convention).
struct Hit {
    int32_t tri;  // 4 bytes
    float t;      // 4 bytes
    float u;      // 4 bytes
    float v;      // 4 bytes: total 16 bytes

    BVHLAB_HD static Hit miss() { return {-1, 0.0f, 0.0f, 0.0f}; }
    BVHLAB_HD bool is_hit() const { return tri >= 0; }
};
static_assert(sizeof(Hit) == 16, "Hit is a 16-byte file record");

/// Which query a ray set asks for.
enum class Query : uint32_t { kClosest = 0, kAny = 1 };

}  // namespace bvhlab::trav
