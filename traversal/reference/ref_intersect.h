// SPDX-License-Identifier: MIT
// Double-precision reference ray/triangle intersection (Moller & Trumbore 1997) and a
// brute-force tracer, for tests of the float kernels.
#pragma once

#include <cmath>
#include <cstddef>

#include "scene/mesh.h"
#include "traversal/device/ray.h"

namespace bvhlab::trav {

/// Double-precision t and barycentrics (Embree's convention) of the point where `ray`'s line
/// meets the plane of (v0, v1, v2), inside the triangle or not. Returns false for parallel rays.
inline bool plane_hit_reference(const Ray& ray, Vec3 v0, Vec3 v1, Vec3 v2, double& t, double& u, double& v) {
    double o[3] = {ray.org.x, ray.org.y, ray.org.z}, d[3] = {ray.dir.x, ray.dir.y, ray.dir.z};
    double e1[3], e2[3], s[3];
    for (int k = 0; k < 3; ++k) {
        e1[k] = double(v1[k]) - v0[k];
        e2[k] = double(v2[k]) - v0[k];
        s[k] = o[k] - v0[k];
    }
    double p[3] = {d[1] * e2[2] - d[2] * e2[1], d[2] * e2[0] - d[0] * e2[2], d[0] * e2[1] - d[1] * e2[0]};
    double det = e1[0] * p[0] + e1[1] * p[1] + e1[2] * p[2];
    if (det == 0.0) return false;
    double inv = 1.0 / det;
    u = (s[0] * p[0] + s[1] * p[1] + s[2] * p[2]) * inv;
    double q[3] = {s[1] * e1[2] - s[2] * e1[1], s[2] * e1[0] - s[0] * e1[2], s[0] * e1[1] - s[1] * e1[0]};
    v = (d[0] * q[0] + d[1] * q[1] + d[2] * q[2]) * inv;
    t = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) * inv;
    return true;
}

/// Double-precision hit of `ray` with (v0, v1, v2) for t in (tmin, tmax).
inline bool intersect_reference(const Ray& ray, Vec3 v0, Vec3 v1, Vec3 v2, double& t, double& u, double& v) {
    return plane_hit_reference(ray, v0, v1, v2, t, u, v) && u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > ray.tmin &&
           t < ray.tmax;
}

/// Closest hit over every triangle of `mesh`, in double precision. O(triangles) per ray.
inline Hit trace_brute_force(const scene::TriangleMesh& mesh, const Ray& ray) {
    Hit best = Hit::miss();
    double best_t = INFINITY;
    for (size_t i = 0; i < mesh.triangle_count(); ++i) {
        double t, u, v;
        if (intersect_reference(ray, mesh.vertex(i, 0), mesh.vertex(i, 1), mesh.vertex(i, 2), t, u, v) && t < best_t) {
            best_t = t;
            best = {int32_t(i), float(t), float(u), float(v)};
        }
    }
    return best;
}

}  // namespace bvhlab::trav
