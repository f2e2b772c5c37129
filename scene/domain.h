// SPDX-License-Identifier: MIT
// The numeric domain bvhlab supports, measured against Embree (the oracle) and float32
// traversal (experiments/NOTES.md, session 20): scenes, rays, cameras and radiances outside it
// are refused with one line naming the value, before any work starts. README "Numeric domain".
#pragma once

#include <string>

#include "accel/core/vec3.h"

namespace bvhlab::scene {

/// The largest magnitude of a vertex coordinate, ray origin or direction component, camera
/// position, aperture or focus distance. Embree aborts on ray values above 1.8e18 and drops
/// triangles near it; on generated scenes it missed hits that the double-precision reference
/// confirms from 1e12 on (1e11 was exact).
constexpr float kMaxCoordinate = 1e10f;
/// The smallest bounding-box diagonal of a scene: from 1e-10 down Embree's shadow rays are
/// invalid (it aborts), and at 1e-20 surface areas are denormal (1e-9 was exact).
constexpr float kMinSceneDiagonal = 1e-8f;
/// The largest radiance of an emitter or an environment map texel (after --env-scale): sums
/// over samples and bounces stay far from float overflow.
constexpr float kMaxRadiance = 1e20f;

/// "" when every component of v is within +-limit (NaN never is), else "<what> (x, y, z) is
/// outside [-limit, limit]".
std::string vec_problem(const char* what, Vec3 v, float limit = kMaxCoordinate);

}  // namespace bvhlab::scene
