// SPDX-License-Identifier: MIT
// Seeded ray generators: primary (pinhole, fish-eye or panorama), ambient occlusion, diffuse bounce and shadow.
// Defaults follow ray_protocol in the scenes' scenes.json. Same arguments, same bytes.
#pragma once

#include <glm/vec3.hpp>

#include <cstdint>
#include <vector>

#include "scene/mesh.h"
#include "traversal/device/projection.h"
#include "traversal/device/ray.h"

namespace bvhlab::trav {

/// A camera: where it is and looks, and its projection. fov_y_deg is the perspective camera's
/// full vertical field of view; fisheye_fov_deg the fish-eye's across the circle inscribed in
/// the image (projection.h).
struct Camera {
    glm::vec3 eye{0.0f, 0.0f, 1.0f};
    glm::vec3 target{0.0f, 0.0f, 0.0f};
    glm::vec3 up{0.0f, 1.0f, 0.0f};
    float fov_y_deg = 45.0f;
    Projection projection = Projection::kPerspective;
    float fisheye_fov_deg = 180.0f;
};

/// "pinhole", "fisheye" or "panorama".
const char* projection_name(Projection p);

/// A camera for scenes without one: looks at the bounds' centre from a raised diagonal
/// (direction (0.5, 0.7, 1)), far enough that the bounding sphere fills the 45-degree view.
Camera framing_camera(const scene::TriangleMesh& mesh);

struct PrimaryConfig {
    uint32_t width = 1024;
    uint32_t height = 768;
    uint32_t samples = 1;  ///< per pixel, on a regular sqrt(S) x sqrt(S) sub-grid; a square
    uint32_t tile = 0;     ///< 0: row-major pixels; T: T x T pixel tiles, row-major within
};

/// One ray per sample, pixels in row-major or tile order, a pixel's samples consecutive.
/// Throws bvhlab::Error on a non-square sample count, a zero size or a degenerate camera.
std::vector<Ray> generate_primary(const Camera& cam, const PrimaryConfig& cfg);

/// Settings of the rays spawned from primary hits.
struct SecondaryConfig {
    uint32_t per_hit = 8;  ///< rays per primary hit (AO and diffuse)
    float offset = 0.0f;   ///< origin offset along the geometric normal (1e-4 x diagonal)
    float tmax = 1.0f;     ///< AO length; diffuse rays use +inf
    uint64_t seed = 1;
};

/// Cosine-weighted hemisphere rays around each hit's geometric normal (facing the incoming
/// ray), tmax = cfg.tmax. For any-hit queries.
std::vector<Ray> generate_ao(const scene::TriangleMesh& mesh, const std::vector<Ray>& primary,
                             const std::vector<Hit>& hits, const SecondaryConfig& cfg);
/// Like generate_ao with tmax = +inf. For closest-hit queries.
std::vector<Ray> generate_diffuse(const scene::TriangleMesh& mesh, const std::vector<Ray>& primary,
                                  const std::vector<Hit>& hits, const SecondaryConfig& cfg);
/// One ray per hit towards `light`, tmax = the distance to it. For any-hit queries.
std::vector<Ray> generate_shadow(const scene::TriangleMesh& mesh, const std::vector<Ray>& primary,
                                 const std::vector<Hit>& hits, Vec3 light, float offset);

/// Hit point and the unit geometric normal turned towards the ray's origin side.
void hit_frame(const scene::TriangleMesh& mesh, const Ray& ray, const Hit& hit, Vec3& point, Vec3& normal);

}  // namespace bvhlab::trav
