// SPDX-License-Identifier: MIT
// Woop's unit-triangle intersection (Woop 2004; as used by Aila & Laine 2009): each triangle
// stores the affine map from world space to the space where it is the unit triangle.
#pragma once

#include <cmath>
#include <cstdint>

#include "accel/core/hd.h"
#include "accel/core/vec3.h"

namespace bvhlab::accel {

/// The inverse of M = [e1 e2 n | v0], where e1 = v1 - v0, e2 = v2 - v0 and n is the unit
/// normal, as three rows of 4 floats (48 bytes, three 16-byte loads on the GPU):
///   row 0 = ( r_w, r_w . v0)   the plane row: t = (row0.w - row0.xyz . o) / (row0.xyz . d)
///   row 1 = ( r_u, -r_u . v0)  u = row1.w + row1.xyz . (o + t d)
///   row 2 = ( r_v, -r_v . v0)  v = row2.w + row2.xyz . (o + t d)
/// The hit point is (1 - u - v) v0 + u v1 + v v2, the same barycentrics Embree reports.
struct alignas(16) WoopTriangle {
    float row[3][4];  // 48 bytes: total 48 bytes

    /// Intersects the ray o + t d with t in (tmin, tmax). On a hit writes t, u, v and
    /// returns true. Parallel rays give a NaN or infinite t, which the comparisons reject.
    BVHLAB_HD BVHLAB_FORCEINLINE bool intersect(Vec3 o, Vec3 d, float tmin, float tmax, float& t_out, float& u_out,
                                                float& v_out) const {
        return intersect_rows(row[0], row[1], row[2], o, d, tmin, tmax, t_out, u_out, v_out);
    }

    /// The same test on three rows held elsewhere: the GPU kernels load them as three
    /// 16-byte read-only loads and call this, so every tracer shares one triangle test.
    BVHLAB_HD BVHLAB_FORCEINLINE static bool intersect_rows(const float* r0, const float* r1, const float* r2, Vec3 o,
                                                            Vec3 d, float tmin, float tmax, float& t_out, float& u_out,
                                                            float& v_out) {
        const float oz = r0[3] - (o.x * r0[0] + o.y * r0[1] + o.z * r0[2]);
        const float dz = d.x * r0[0] + d.y * r0[1] + d.z * r0[2];
        const float t = oz / dz;
        if (!(t > tmin && t < tmax)) return false;
        const float ox = r1[3] + o.x * r1[0] + o.y * r1[1] + o.z * r1[2];
        const float dx = d.x * r1[0] + d.y * r1[1] + d.z * r1[2];
        const float u = ox + t * dx;
        if (!(u >= 0.0f)) return false;
        const float oy = r2[3] + o.x * r2[0] + o.y * r2[1] + o.z * r2[2];
        const float dy = d.x * r2[0] + d.y * r2[1] + d.z * r2[2];
        const float v = oy + t * dy;
        if (!(v >= 0.0f && u + v <= 1.0f)) return false;
        t_out = t;
        u_out = u;
        v_out = v;
        return true;
    }
};
static_assert(sizeof(WoopTriangle) == 48 && alignof(WoopTriangle) == 16, "WoopTriangle layout");

/// The map of triangle (v0, v1, v2), computed in double precision and rounded to float, into
/// `w`; false (and `w` untouched) for a triangle of zero area. Host and device share it: the
/// GPU builders' file is compiled without FMA contraction, so both give the same bits.
BVHLAB_HD inline bool woop_map(Vec3 v0, Vec3 v1, Vec3 v2, WoopTriangle& w) {
    double e1[3], e2[3], n[3], p[3];
    for (int k = 0; k < 3; ++k) {
        e1[k] = double(v1[k]) - double(v0[k]);
        e2[k] = double(v2[k]) - double(v0[k]);
        p[k] = v0[k];
    }
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    const double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(len > 0.0)) return false;
    for (double& x : n) x /= len;
    // Columns of M are e1, e2, n; invert by cofactors: rows of M^-1 are (e2 x n, n x e1,
    // e1 x e2) / det.
    double rw[3], ru[3], rv[3];
    ru[0] = e2[1] * n[2] - e2[2] * n[1];
    ru[1] = e2[2] * n[0] - e2[0] * n[2];
    ru[2] = e2[0] * n[1] - e2[1] * n[0];
    rv[0] = n[1] * e1[2] - n[2] * e1[1];
    rv[1] = n[2] * e1[0] - n[0] * e1[2];
    rv[2] = n[0] * e1[1] - n[1] * e1[0];
    rw[0] = e1[1] * e2[2] - e1[2] * e2[1];
    rw[1] = e1[2] * e2[0] - e1[0] * e2[2];
    rw[2] = e1[0] * e2[1] - e1[1] * e2[0];
    const double det = e1[0] * ru[0] + e1[1] * ru[1] + e1[2] * ru[2];
    const double* rows[3] = {rw, ru, rv};
    for (int r = 0; r < 3; ++r) {
        double dotp = 0.0;
        for (int k = 0; k < 3; ++k) {
            w.row[r][k] = float(rows[r][k] / det);
            dotp += rows[r][k] / det * p[k];
        }
        w.row[r][3] = float(r == 0 ? dotp : -dotp);
    }
    return true;
}

/// Computes the map for triangle (v0, v1, v2) (woop_map). The triangle must have non-zero
/// area.
WoopTriangle make_woop_triangle(Vec3 v0, Vec3 v1, Vec3 v2);

}  // namespace bvhlab::accel
