// SPDX-License-Identifier: MIT
// Normal and height maps: the shading normal bent by a texture, in the frame that the triangle's
// texture coordinates give it (a tangent along +u, a bitangent along +v, per triangle). Host and
// device code, read by both integrators through mapped_normal (renderer/core/stages.h).
#pragma once

#include "accel/core/hd.h"
#include "accel/core/vec3.h"
#include "renderer/core/texture.h"

namespace bvhlab::render {

/// dp/du and dp/dv of the triangle with corners p0, p1, p2 and texture coordinates uv (u0, v0,
/// u1, v1, u2, v2): the world-space change of the position per unit of u and of v. False when the
/// texture coordinates do not span a plane (a zero or non-finite determinant).
BVHLAB_HD inline bool uv_derivatives(Vec3 p0, Vec3 p1, Vec3 p2, const float* uv, Vec3& dpdu, Vec3& dpdv) {
    const float du1 = uv[2] - uv[0], dv1 = uv[3] - uv[1];
    const float du2 = uv[4] - uv[0], dv2 = uv[5] - uv[1];
    const float det = du1 * dv2 - dv1 * du2;
    if (!(fabsf(det) > 1e-12f) || !(det - det == 0.0f)) return false;
    const Vec3 e1 = p1 - p0, e2 = p2 - p0;
    const float inv = 1.0f / det;
    dpdu = (e1 * dv2 - e2 * dv1) * inv;
    dpdv = (e2 * du1 - e1 * du2) * inv;
    const float check = dpdu.x + dpdu.y + dpdu.z + dpdv.x + dpdv.y + dpdv.z;
    return check - check == 0.0f;
}

/// The normal that a tangent-space normal-map texel gives around the unit normal n: the texel
/// holds (t + 1) / 2 of a unit vector t whose x runs along the tangent (n's part of dpdu taken
/// out), y along the bitangent (n x tangent, turned towards dpdv: mirrored texture coordinates
/// keep +v up) and z along n. `scale` (-bm) multiplies t's x and y. The result has unit length
/// and lies on n's side; n itself where the frame or the texel is degenerate.
BVHLAB_HD inline Vec3 tangent_space_normal(Vec3 n, Vec3 dpdu, Vec3 dpdv, Vec3 texel, float scale) {
    const Vec3 t_raw = dpdu - n * dot(n, dpdu);
    const float tl = length(t_raw);
    if (!(tl > 1e-12f * length(dpdu))) return n;
    const Vec3 t = t_raw * (1.0f / tl);
    Vec3 b = cross(n, t);
    if (dot(b, dpdv) < 0.0f) b = b * -1.0f;
    const float x = (2.0f * texel.x - 1.0f) * scale, y = (2.0f * texel.y - 1.0f) * scale, z = 2.0f * texel.z - 1.0f;
    const Vec3 m = t * x + b * y + n * z;
    const float ml = length(m);
    if (!(ml > 1e-6f) || !(dot(m, n) > 0.0f)) return n;
    return m * (1.0f / ml);
}

/// The normal of the surface displaced along the unit normal n by a height h(u, v) whose
/// derivatives are hu = dh/du and hv = dh/dv: n - grad h, with the gradient taken in the plane
/// that dpdu and dpdv span (the dual basis of the two; Mikkelsen 2020, "Surface gradient-based
/// bump mapping"). Unit length, on n's side; n itself where dpdu and dpdv are parallel.
BVHLAB_HD inline Vec3 height_normal(Vec3 n, Vec3 dpdu, Vec3 dpdv, float hu, float hv) {
    const float d = dot(n, cross(dpdu, dpdv));
    if (!(fabsf(d) > 1e-20f)) return n;
    const Vec3 grad = (cross(dpdv, n) * hu + cross(n, dpdu) * hv) * (1.0f / d);
    const Vec3 m = n - grad;
    const float ml = length(m);
    if (!(ml > 1e-6f) || !(ml - ml == 0.0f)) return n;
    return m * (1.0f / ml);
}

/// A height map's height at (u, v): the mean of the bilinear lookup's channels.
BVHLAB_HD inline float map_height(const Vec3* texels, const TextureInfo& t, float u, float v) {
    const Vec3 c = sample_texture(texels, t, u, v);
    return (c.x + c.y + c.z) * (1.0f / 3.0f);
}

/// A height map's slope texture, made once on the host: texel (i, j) holds the central
/// differences one texel either side, (h[i + 1] - h[i - 1]) / 2du and (h[j up] - h[j down]) / 2dv
/// (per unit of u and of v; h the mean of a texel's channels; repeat wrapping), and 0. Its
/// bilinear lookup at (u, v) equals the central differences of map_height at (u, v), one texel
/// either side: the four lookups of those share their weights, so the differences commute with
/// the interpolation. One lookup of 4 texels instead of four (12 texels).
inline void height_slopes(const Vec3* heights, uint32_t width, uint32_t height, Vec3* slopes) {
    const int w = int(width), h = int(height);
    auto at = [&](int x, int y) {
        const Vec3 c = heights[size_t(wrap_index(y, h)) * width + size_t(wrap_index(x, w))];
        return (c.x + c.y + c.z) * (1.0f / 3.0f);
    };
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)  // rows run down the image: +v is one row up
            slopes[size_t(y) * width + size_t(x)] = {(at(x + 1, y) - at(x - 1, y)) * (0.5f * float(w)),
                                                     (at(x, y - 1) - at(x, y + 1)) * (0.5f * float(h)), 0.0f};
}

/// The derivatives of scale * height at (u, v), hu = dh/du and hv = dh/dv, from the slope
/// texture `t` (height_slopes).
BVHLAB_HD inline void height_derivatives(const Vec3* slopes, const TextureInfo& t, float u, float v, float scale,
                                         float& hu, float& hv) {
    const Vec3 s = sample_texture(slopes, t, u, v);
    hu = scale * s.x;
    hv = scale * s.y;
}

}  // namespace bvhlab::render
