// SPDX-License-Identifier: MIT
// map_Kd textures: every texture's texels in one array, looked up bilinearly with repeat
// wrapping. Host and device code; the host loads the images (RenderScene) and both
// integrators read them through TextureView.
#pragma once

#include <cstdint>

#include "accel/core/hd.h"
#include "accel/core/vec3.h"

namespace bvhlab::render {

/// Where one texture's texels start in the shared array, and its size.
struct TextureInfo {
    uint32_t offset;  ///< first texel, row-major, top row first (as Image)
    uint32_t width, height;
    uint32_t pad;
};
static_assert(sizeof(TextureInfo) == 16, "TextureInfo is 16 bytes");

struct TextureView {
    const Vec3* texels;       ///< linear RGB of every texture, back to back
    const TextureInfo* info;  ///< one per texture; RenderMaterial::texture indexes it
    const float* texcoords;   ///< 6 per triangle (TriangleMesh::texcoords), or null: no texture applies
};

/// i wrapped into [0, n) (repeat): a comparison for the indices a lookup usually asks for, an
/// integer division (slow on the GPU) only for the others.
BVHLAB_HD inline int wrap_index(int i, int n) {
    if (i >= 0 && i < n) return i;
    i %= n;
    return i < 0 ? i + n : i;
}

/// The texel (x, y) with repeat wrapping of any integer coordinate.
BVHLAB_HD inline Vec3 texel_wrapped(const Vec3* texels, const TextureInfo& t, int x, int y) {
    x = wrap_index(x, int(t.width));
    y = wrap_index(y, int(t.height));
    return texels[t.offset + uint32_t(y) * t.width + uint32_t(x)];
}

/// Bilinear lookup at texture coordinates (u, v): u runs left to right, v bottom to top (OBJ's
/// convention; the image's top row is v = 1), both repeating with period 1. Texel centres sit at
/// (i + 0.5) / size. A non-finite coordinate reads as 0.
BVHLAB_HD inline Vec3 sample_texture(const Vec3* texels, const TextureInfo& t, float u, float v) {
    if (!(u - u == 0.0f)) u = 0.0f;  // NaN or inf
    if (!(v - v == 0.0f)) v = 0.0f;
    u -= floorf(u);
    v -= floorf(v);
    const float x = u * float(t.width) - 0.5f, y = (1.0f - v) * float(t.height) - 0.5f;
    const float fx = floorf(x), fy = floorf(y);
    const float ax = x - fx, ay = y - fy;
    const int x0 = int(fx), y0 = int(fy);
    const Vec3 top = texel_wrapped(texels, t, x0, y0) * (1.0f - ax) + texel_wrapped(texels, t, x0 + 1, y0) * ax;
    const Vec3 bottom =
        texel_wrapped(texels, t, x0, y0 + 1) * (1.0f - ax) + texel_wrapped(texels, t, x0 + 1, y0 + 1) * ax;
    return top * (1.0f - ay) + bottom * ay;
}

/// The texture coordinates of the point with barycentrics (b1, b2) on triangle `tri`.
BVHLAB_HD inline void triangle_texcoords(const float* texcoords, uint32_t tri, float b1, float b2, float& u, float& v) {
    const float* c = texcoords + 6 * size_t(tri);
    const float b0 = 1.0f - b1 - b2;
    u = b0 * c[0] + b1 * c[2] + b2 * c[4];
    v = b0 * c[1] + b1 * c[3] + b2 * c[5];
}

}  // namespace bvhlab::render
