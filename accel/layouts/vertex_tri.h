// SPDX-License-Identifier: MIT
// A triangle as its first vertex and two edges (36 bytes), tested by Moller & Trumbore (1997):
// the CWBVH's smaller leaf format (--cw-tris vertices), 0.75x the bytes of a WoopTriangle.
#pragma once

#include <cstdint>

#include "accel/core/hd.h"
#include "accel/core/vec3.h"

namespace bvhlab::accel {

/// v0, e1 = v1 - v0 and e2 = v2 - v0 as nine floats (no padding: nine 4-byte loads on the GPU).
/// The hit point is (1 - u - v) v0 + u v1 + v v2, the barycentrics WoopTriangle and Embree use.
struct VertexTriangle {
    float f[9];  // v0.xyz, e1.xyz, e2.xyz

    BVHLAB_HD BVHLAB_FORCEINLINE bool intersect(Vec3 o, Vec3 d, float tmin, float tmax, float& t_out, float& u_out,
                                                float& v_out) const {
        return intersect_values(f, o, d, tmin, tmax, t_out, u_out, v_out);
    }

    /// The test on nine values held elsewhere (the GPU kernels load them read-only and call
    /// this). A degenerate or parallel triangle gives det = 0 and a NaN or infinite u, v or t,
    /// which the comparisons reject.
    BVHLAB_HD BVHLAB_FORCEINLINE static bool intersect_values(const float* f, Vec3 o, Vec3 d, float tmin, float tmax,
                                                              float& t_out, float& u_out, float& v_out) {
        const Vec3 e1{f[3], f[4], f[5]}, e2{f[6], f[7], f[8]};
        const Vec3 p = cross(d, e2);
        const float inv_det = 1.0f / dot(e1, p);
        const Vec3 s{o.x - f[0], o.y - f[1], o.z - f[2]};
        const float u = dot(s, p) * inv_det;
        if (!(u >= 0.0f && u <= 1.0f)) return false;
        const Vec3 q = cross(s, e1);
        const float v = dot(d, q) * inv_det;
        if (!(v >= 0.0f && u + v <= 1.0f)) return false;
        const float t = dot(e2, q) * inv_det;
        if (!(t > tmin && t < tmax)) return false;
        t_out = t;
        u_out = u;
        v_out = v;
        return true;
    }
};
static_assert(sizeof(VertexTriangle) == 36 && alignof(VertexTriangle) == 4, "VertexTriangle layout");

BVHLAB_HD inline VertexTriangle make_vertex_triangle(Vec3 v0, Vec3 v1, Vec3 v2) {
    const Vec3 e1 = v1 - v0, e2 = v2 - v0;
    return {{v0.x, v0.y, v0.z, e1.x, e1.y, e1.z, e2.x, e2.y, e2.z}};
}

}  // namespace bvhlab::accel
