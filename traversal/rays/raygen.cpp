// SPDX-License-Identifier: MIT
// Ray generators. Randomness comes from a counter-based hash of (seed, hit, sample), so
// parallel generation gives the same bytes as serial.
#include "traversal/rays/raygen.h"

#include <tbb/parallel_for.h>

#include <cmath>
#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>

#include "accel/core/check.h"
#include "accel/core/random.h"

namespace bvhlab::trav {
namespace {

/// Orthonormal basis around unit n (Duff et al. 2017, "Building an orthonormal basis, revisited").
void onb(Vec3 n, Vec3& t, Vec3& b) {
    const float s = std::copysign(1.0f, n.z);
    const float a = -1.0f / (s + n.z);
    const float c = n.x * n.y * a;
    t = {1.0f + s * n.x * n.x * a, s * c, -s * n.x};
    b = {c, s + n.y * n.y * a, -n.y};
}

Vec3 to_vec3(glm::vec3 v) { return {v.x, v.y, v.z}; }

/// Offsets of each primary hit's first secondary ray (exclusive prefix sum of hits).
std::vector<size_t> hit_offsets(const std::vector<Hit>& hits, size_t per_hit, size_t& total) {
    std::vector<size_t> off(hits.size());
    total = 0;
    for (size_t i = 0; i < hits.size(); ++i) {
        off[i] = total;
        if (hits[i].is_hit()) total += per_hit;
    }
    return off;
}

std::vector<Ray> hemisphere_rays(const scene::TriangleMesh& mesh, const std::vector<Ray>& primary,
                                 const std::vector<Hit>& hits, const SecondaryConfig& cfg, float tmax) {
    BVHLAB_CHECK(primary.size() == hits.size(), "primary rays and hits differ in count");
    BVHLAB_CHECK(cfg.per_hit > 0, "rays per hit must be at least 1");
    size_t total = 0;
    const std::vector<size_t> off = hit_offsets(hits, cfg.per_hit, total);
    std::vector<Ray> out(total);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, hits.size(), 1024), [&](const auto& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
            if (!hits[i].is_hit()) continue;
            Vec3 p, n, t, b;
            hit_frame(mesh, primary[i], hits[i], p, n);
            onb(n, t, b);
            const Vec3 org = p + n * cfg.offset;
            for (uint32_t k = 0; k < cfg.per_hit; ++k) {
                const uint64_t h = splitmix64(cfg.seed ^ splitmix64(i * 0x100000001b3ull + k));
                const float phi = 6.2831853f * unit_float(h), r2 = unit_float(splitmix64(h));
                const float rad = std::sqrt(r2), z = std::sqrt(std::max(0.0f, 1.0f - r2));
                const Vec3 d = t * (rad * std::cos(phi)) + b * (rad * std::sin(phi)) + n * z;
                out[off[i] + k] = {org, 0.0f, d, tmax};
            }
        }
    });
    return out;
}

}  // namespace

void hit_frame(const scene::TriangleMesh& mesh, const Ray& ray, const Hit& hit, Vec3& point, Vec3& normal) {
    const Vec3 v0 = mesh.vertex(hit.tri, 0), v1 = mesh.vertex(hit.tri, 1), v2 = mesh.vertex(hit.tri, 2);
    // Barycentric interpolation lands on the triangle's plane more precisely than o + t d.
    const double w = 1.0 - double(hit.u) - double(hit.v);
    for (int k = 0; k < 3; ++k) point[k] = float(w * v0[k] + double(hit.u) * v1[k] + double(hit.v) * v2[k]);
    Vec3 n = cross(v1 - v0, v2 - v0);
    n = n * (1.0f / length(n));
    normal = dot(n, ray.dir) > 0.0f ? n * -1.0f : n;
}

Camera framing_camera(const scene::TriangleMesh& mesh) {
    const AABB b = mesh.bounds();
    const Vec3 c = b.center();
    const float radius = 0.5f * length(b.extent());
    Camera cam;
    cam.fov_y_deg = 45.0f;
    const float dist = radius / std::sin(glm::radians(0.5f * cam.fov_y_deg)) * 1.05f;
    cam.target = {c.x, c.y, c.z};
    cam.eye = cam.target + glm::normalize(glm::vec3(0.5f, 0.7f, 1.0f)) * dist;
    cam.up = {0.0f, 1.0f, 0.0f};
    return cam;
}

const char* projection_name(Projection p) {
    switch (p) {
        case Projection::kFisheye:
            return "fisheye";
        case Projection::kPanorama:
            return "panorama";
        default:
            return "pinhole";
    }
}

std::vector<Ray> generate_primary(const Camera& cam, const PrimaryConfig& cfg) {
    BVHLAB_CHECK(cfg.width > 0 && cfg.height > 0, "image size must be at least 1x1");
    const auto grid = uint32_t(std::lround(std::sqrt(double(cfg.samples))));
    BVHLAB_CHECK(cfg.samples > 0 && grid * grid == cfg.samples,
                 "samples per pixel must be a perfect square (1, 4, 9, 16, ...) for the regular sub-grid");
    const bool wide = cam.projection != Projection::kPerspective;
    BVHLAB_CHECK(wide || (cam.fov_y_deg > 0.0f && cam.fov_y_deg < 180.0f), "fov_y must be in (0, 180) degrees");
    BVHLAB_CHECK(
        cam.projection != Projection::kFisheye || (cam.fisheye_fov_deg > 0.0f && cam.fisheye_fov_deg <= 360.0f),
        "the fish-eye's field of view must be in (0, 360] degrees");
    const glm::vec3 fwd = cam.target - cam.eye;
    BVHLAB_CHECK(glm::length(fwd) > 0.0f, "camera eye and target coincide");
    const glm::vec3 w = glm::normalize(fwd);
    const glm::vec3 side = glm::cross(w, cam.up);
    BVHLAB_CHECK(glm::length(side) > 0.0f, "camera up is parallel to the view direction");
    const glm::vec3 u = glm::normalize(side), v = glm::cross(u, w);
    const float half_h = std::tan(glm::radians(cam.fov_y_deg) * 0.5f);
    const float half_w = half_h * float(cfg.width) / float(cfg.height);
    const float half_fisheye = glm::radians(cam.fisheye_fov_deg) * 0.5f;
    const size_t npix = size_t(cfg.width) * cfg.height;
    std::vector<Ray> rays(npix * cfg.samples);
    const uint32_t tile = cfg.tile;
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, cfg.height), [&](const auto& r) {
        for (uint32_t y = r.begin(); y < r.end(); ++y) {
            for (uint32_t x = 0; x < cfg.width; ++x) {
                size_t slot;
                if (tile == 0) {
                    slot = size_t(y) * cfg.width + x;
                } else {
                    // Tiles are row-major; edge tiles are clipped to the image, so the pixels
                    // before tile (tx, ty) are the full tile rows above plus the tiles to its left.
                    const uint32_t ty = y / tile, tx = x / tile;
                    const uint32_t th = std::min(tile, cfg.height - ty * tile);
                    const uint32_t tw = std::min(tile, cfg.width - tx * tile);
                    slot = size_t(ty) * tile * cfg.width + size_t(tx) * tile * th + size_t(y - ty * tile) * tw +
                           (x - tx * tile);
                }
                for (uint32_t s = 0; s < cfg.samples; ++s) {
                    const float sx = (float(s % grid) + 0.5f) / float(grid);
                    const float sy = (float(s / grid) + 0.5f) / float(grid);
                    Vec3 dir;
                    if (wide) {
                        dir = camera_to_world(wide_direction(cam.projection, (float(x) + sx) / float(cfg.width),
                                                             (float(y) + sy) / float(cfg.height),
                                                             float(cfg.width) / float(cfg.height), half_fisheye),
                                              to_vec3(u), to_vec3(v), to_vec3(-w));
                    } else {
                        const float px = (2.0f * (float(x) + sx) / float(cfg.width) - 1.0f) * half_w;
                        const float py = (1.0f - 2.0f * (float(y) + sy) / float(cfg.height)) * half_h;
                        dir = to_vec3(glm::normalize(w + u * px + v * py));
                    }
                    rays[slot * cfg.samples + s] = {to_vec3(cam.eye), 0.0f, dir, INFINITY};
                }
            }
        }
    });
    return rays;
}

std::vector<Ray> generate_ao(const scene::TriangleMesh& mesh, const std::vector<Ray>& primary,
                             const std::vector<Hit>& hits, const SecondaryConfig& cfg) {
    return hemisphere_rays(mesh, primary, hits, cfg, cfg.tmax);
}

std::vector<Ray> generate_diffuse(const scene::TriangleMesh& mesh, const std::vector<Ray>& primary,
                                  const std::vector<Hit>& hits, const SecondaryConfig& cfg) {
    return hemisphere_rays(mesh, primary, hits, cfg, INFINITY);
}

std::vector<Ray> generate_shadow(const scene::TriangleMesh& mesh, const std::vector<Ray>& primary,
                                 const std::vector<Hit>& hits, Vec3 light, float offset) {
    BVHLAB_CHECK(primary.size() == hits.size(), "primary rays and hits differ in count");
    size_t total = 0;
    const std::vector<size_t> off = hit_offsets(hits, 1, total);
    std::vector<Ray> out(total);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, hits.size(), 1024), [&](const auto& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
            if (!hits[i].is_hit()) continue;
            Vec3 p, n;
            hit_frame(mesh, primary[i], hits[i], p, n);
            const Vec3 org = p + n * offset;
            const Vec3 to_light = light - org;
            const float dist = length(to_light);
            out[off[i]] = {org, 0.0f, to_light * (1.0f / dist), dist};
        }
    });
    return out;
}

}  // namespace bvhlab::trav
