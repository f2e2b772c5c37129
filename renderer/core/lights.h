// SPDX-License-Identifier: MIT
// Lights as the integrators sample them: emissive triangles picked in proportion to power
// (area x luminance of Ke) through an alias table (Walker 1977, Vose 1991), and the sky.
#pragma once

#include <cstdint>

#include "renderer/core/environment.h"
#include "renderer/core/sampling.h"

namespace bvhlab::render {

/// One entry of the alias table: keep this index with probability `keep`, else take `alias`.
struct AliasEntry {
    float keep;
    uint32_t alias;
};

struct LightView {
    const uint32_t* tris = nullptr;     ///< emissive triangle ids, one per light
    const AliasEntry* table = nullptr;  ///< over the lights, by power
    const float* pick_pdf = nullptr;    ///< per mesh triangle: its probability among the lights (0: not a light)
    uint32_t count = 0;
    Vec3 sky{0.0f, 0.0f, 0.0f};  ///< constant radiance of every direction no triangle covers
    EnvView env;                 ///< a lat-long environment map instead of the constant sky
    float sky_pick = 0.0f;       ///< probability that next-event estimation picks the sky
};

/// The light index that uniform u in [0, 1) picks from an alias table of n > 0 entries.
BVHLAB_HD inline uint32_t alias_pick(const AliasEntry* table, uint32_t n, float u) {
    const float x = u * float(n);
    uint32_t i = uint32_t(x);
    if (i >= n) i = n - 1;
    return (x - float(i)) < table[i].keep ? i : table[i].alias;
}

/// Whether rays that leave the scene see any light.
BVHLAB_HD inline bool has_sky(const LightView& l) { return l.env.present() || max3(l.sky) > 0.0f; }

/// Radiance from direction d (unit) where no triangle is hit.
BVHLAB_HD inline Vec3 sky_radiance(const LightView& l, Vec3 d) {
    return l.env.present() ? env_radiance(l.env, d) : l.sky;
}

/// Density (solid angle) with which next-event estimation samples the sky direction d: by the
/// environment map's importance, or uniformly over the sphere for a constant sky.
BVHLAB_HD inline float sky_direction_pdf(const LightView& l, Vec3 d) {
    return l.sky_pick * (l.env.present() ? env_pdf(l.env, d) : 1.0f / (4.0f * kPi));
}

/// Density (solid angle) with which next-event estimation samples the point of triangle `tri`
/// of area `area` seen at distance `dist` under cosine `cos_light` (> 0).
BVHLAB_HD inline float triangle_light_pdf(const LightView& l, uint32_t tri, float area, float dist, float cos_light) {
    return (1.0f - l.sky_pick) * l.pick_pdf[tri] / area * dist * dist / cos_light;
}

}  // namespace bvhlab::render
