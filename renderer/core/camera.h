// SPDX-License-Identifier: MIT
// The render camera: jittered sub-pixel samples, a thin lens and a shutter interval over which
// the eye moves; or a fish-eye or panorama projection (traversal/device/projection.h). Host and device code; the host
// fills CameraData once per render.
#pragma once

#include <cstdint>

#include "renderer/core/sampling.h"
#include "traversal/device/projection.h"
#include "traversal/device/ray.h"

namespace bvhlab::render {

struct CameraData {
    Vec3 eye0;             ///< eye at shutter time 0
    Vec3 eye1;             ///< eye at shutter time 1 (= eye0 for a still camera)
    Vec3 right, up, back;  ///< orthonormal; the view looks along -back
    float tan_half_fov_y;
    float aspect;                       ///< width / height
    float lens_radius;                  ///< 0: pinhole
    float focus_distance;               ///< along the view axis
    float shutter_open, shutter_close;  ///< in [0, 1]: the part of the eye's motion the frame sees
    uint32_t width, height;
    uint32_t pixel_centres;  ///< 1: every sample through its pixel's centre (no anti-aliasing)
    trav::Projection projection = trav::Projection::kPerspective;  ///< fish-eye and panorama: no lens
    float half_fov = 0.0f;                                         ///< the fish-eye's half field of view in radians
};

/// Whether every sample of a pixel gets the same camera ray: pixel centres, a pinhole and an
/// eye that does not move. The first-hit cache needs it.
BVHLAB_HD inline bool camera_rays_repeat(const CameraData& c) {
    return c.pixel_centres && c.lens_radius == 0.0f && c.eye0.x == c.eye1.x && c.eye0.y == c.eye1.y &&
           c.eye0.z == c.eye1.z;
}

/// The ray of one sample of pixel `pixel` (row-major), with its numbers from rand01.
BVHLAB_HD inline trav::Ray camera_ray(const CameraData& c, uint32_t pixel, uint32_t sample, uint32_t seed) {
    const uint32_t x = pixel % c.width, y = pixel / c.width;
    const float jx = c.pixel_centres ? 0.5f : rand01(pixel, sample, kDimPixelX, seed);
    const float jy = c.pixel_centres ? 0.5f : rand01(pixel, sample, kDimPixelY, seed);
    const float sx = (2.0f * (float(x) + jx) / float(c.width) - 1.0f) * c.tan_half_fov_y * c.aspect;
    const float sy = (1.0f - 2.0f * (float(y) + jy) / float(c.height)) * c.tan_half_fov_y;
    const float ut = rand01(pixel, sample, kDimTime, seed);
    const float time = c.shutter_open + (c.shutter_close - c.shutter_open) * ut;
    const Vec3 eye = c.eye0 + (c.eye1 - c.eye0) * time;
    if (c.projection != trav::Projection::kPerspective) {
        const Vec3 d = trav::wide_direction(c.projection, (float(x) + jx) / float(c.width),
                                            (float(y) + jy) / float(c.height), c.aspect, c.half_fov);
        return {eye, 0.0f, trav::camera_to_world(d, c.right, c.up, c.back), INFINITY};
    }
    Vec3 dir = normalize(c.right * sx + c.up * sy - c.back);
    Vec3 org = eye;
    if (c.lens_radius > 0.0f) {
        // The focus plane is at focus_distance along the view axis; dot(dir, -back) > 0.
        const Vec3 focus = eye + dir * (c.focus_distance / dot(dir, c.back * -1.0f));
        float lx, ly;
        sample_disk(rand01(pixel, sample, kDimLensU, seed), rand01(pixel, sample, kDimLensV, seed), lx, ly);
        org = eye + c.right * (lx * c.lens_radius) + c.up * (ly * c.lens_radius);
        dir = normalize(focus - org);
    }
    return {org, 0.0f, dir, INFINITY};
}

}  // namespace bvhlab::render
