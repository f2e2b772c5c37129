// SPDX-License-Identifier: MIT
// Camera projections beyond the perspective one, written once for the ray generators (host)
// and the path tracer (host and device): an equidistant fish-eye and an equirectangular
// panorama. The perspective camera keeps its own code in both places, so that its rays stay
// the bytes they were.
#pragma once

#include <cstdint>

#include "accel/core/hd.h"
#include "accel/core/vec3.h"

namespace bvhlab::trav {

enum class Projection : uint32_t {
    kPerspective = 0,  ///< pinhole (or thin lens): the vertical field of view is fov_y
    kFisheye = 1,      ///< equidistant: the angle from the view axis grows linearly with the distance from the centre
    kPanorama = 2,     ///< equirectangular: 360 degrees across, 180 degrees down
};

/// The direction through image point (u, v) in [0, 1]^2 (u to the right, v downwards) in
/// camera space: x right, y up, z backwards (the view looks along -z). Unit length.
/// - fisheye: r = the distance from the image centre in units of half the image height (pixels
///   are square: x runs to +-aspect), angle from the view axis theta = r * half_fov, around
///   the axis at the point's polar angle. With half_fov = 90 degrees the circle inscribed in the
///   image sees the hemisphere ahead; the corners see past it.
/// - panorama: longitude (u - 1/2) * 2 pi (0 straight ahead, positive to the right), latitude
///   (1/2 - v) * pi (positive up).
BVHLAB_HD inline Vec3 wide_direction(Projection p, float u, float v, float aspect, float half_fov_rad) {
    if (p == Projection::kPanorama) {
        const float lon = (u - 0.5f) * 6.28318530717958647f;
        const float lat = (0.5f - v) * 3.14159265358979324f;
        const float c = cosf(lat);
        return {sinf(lon) * c, sinf(lat), -cosf(lon) * c};
    }
    const float x = (2.0f * u - 1.0f) * aspect, y = 1.0f - 2.0f * v;
    const float r = sqrtf(x * x + y * y);
    if (r == 0.0f) return {0.0f, 0.0f, -1.0f};
    const float theta = r * half_fov_rad, s = sinf(theta) / r;
    return {x * s, y * s, -cosf(theta)};
}

/// Camera space to world space: right, up and back are the camera's orthonormal axes.
BVHLAB_HD inline Vec3 camera_to_world(Vec3 d, Vec3 right, Vec3 up, Vec3 back) {
    return right * d.x + up * d.y + back * d.z;
}

}  // namespace bvhlab::trav
