// SPDX-License-Identifier: MIT
// Ray and hit records shared by the CPU tracer, the GPU kernels, the Embree oracle and the
// ray/hit files. Both are plain data whose bytes are the file records.
#pragma once

#include <cstddef>
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

// Record i of a device array as 16-byte accesses (two for a ray, one for a hit): a struct copy
// compiles to 4-byte accesses, 8 per ray, each touching a warp's 32 records 32 bytes apart
// (NOTES.md, session 16: the render's generate stage ran at 3.5x its DRAM bound that way).
// The loads go through the read-only path: never for an array the same kernel writes. On the
// host, plain copies. Device arrays come from cudaMalloc, so records are 16-byte aligned.

BVHLAB_HD inline Ray load_ray(const Ray* rays, size_t i) {
#if defined(__CUDA_ARCH__)
    const float4* p = reinterpret_cast<const float4*>(rays + i);
    const float4 a = __ldg(p), b = __ldg(p + 1);
    return {{a.x, a.y, a.z}, a.w, {b.x, b.y, b.z}, b.w};
#else
    return rays[i];
#endif
}

BVHLAB_HD inline void store_ray(Ray* rays, size_t i, const Ray& r) {
#if defined(__CUDA_ARCH__)
    float4* p = reinterpret_cast<float4*>(rays + i);
    p[0] = make_float4(r.org.x, r.org.y, r.org.z, r.tmin);
    p[1] = make_float4(r.dir.x, r.dir.y, r.dir.z, r.tmax);
#else
    rays[i] = r;
#endif
}

BVHLAB_HD inline Hit load_hit(const Hit* hits, size_t i) {
#if defined(__CUDA_ARCH__)
    const float4 a = __ldg(reinterpret_cast<const float4*>(hits + i));
    return {__float_as_int(a.x), a.y, a.z, a.w};
#else
    return hits[i];
#endif
}

BVHLAB_HD inline void store_hit(Hit* hits, size_t i, const Hit& h) {
#if defined(__CUDA_ARCH__)
    reinterpret_cast<float4*>(hits)[i] = make_float4(__int_as_float(h.tri), h.t, h.u, h.v);
#else
    hits[i] = h;
#endif
}

}  // namespace bvhlab::trav
