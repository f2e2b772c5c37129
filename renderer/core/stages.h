// SPDX-License-Identifier: MIT
// The wavefront integrator's per-path stages (Laine, Karras & Aila 2013, "Megakernels
// considered harmful"), written once for both devices: the CPU driver calls them in a TBB loop,
// the GPU driver from one small kernel each. Path state is structure-of-arrays; a stage reads
// and writes only entry i, and the radiance of its path's slot. A pass (a "wave") traces
// `samples` samples of every pixel at once: path slot s is pixel s % pixels, sample
// first_sample + s / pixels, so that each trace launch holds millions of rays even for small
// images (NOTES.md, session 15: one sample per pass left the H100 idle between launches). Tracing and compaction are
// the drivers' own (Embree or a registry kernel; a serial pack or CUB).
#pragma once

#include <cstdint>

#include "renderer/core/bsdf.h"
#include "renderer/core/camera.h"
#include "renderer/core/lights.h"
#include "renderer/core/normal_map.h"
#include "renderer/core/texture.h"

namespace bvhlab::render {

/// How emitters are reached. kMis is the renderer; the other two exist so that tests can check
/// that both strategies alone converge to the same image as their combination.
enum class Strategy : uint32_t { kMis = 0, kBsdfOnly = 1, kLightOnly = 2 };

/// Deliberate bugs for the tests that prove the CPU/GPU comparison can fail: planted only
/// through renderer/testing.h (ScopedPlantedBug), which the drivers read into PathParams.
/// kNoCosine: light samples lose the cosine; kBsdfWeightOne: emitters found by BSDF sampling
/// keep weight 1 under MIS, so direct light is counted twice.
enum class PlantedBug : uint32_t { kNone = 0, kNoCosine = 1, kBsdfWeightOne = 2 };

struct SceneView {
    const Vec3* vertices;
    const uint32_t* indices;
    const int32_t* material_ids;      ///< per triangle, -1 for none
    const Vec3* normals;              ///< shading normals, 3 per triangle (TriangleMesh::normals), or null
    const RenderMaterial* materials;  ///< [0] is the default material, then the mesh's
    LightView lights;
    TextureView textures;
    float offset;  ///< spawned rays start this far off the surface
};

struct PathParams {
    uint32_t max_depth;  ///< most segments per path (1: camera rays only)
    uint32_t rr_depth;   ///< Russian roulette from this bounce on
    uint32_t seed;
    uint32_t first_sample;  ///< the pass's first sample index
    uint32_t pixels;        ///< pixels of the image: slot s is pixel s % pixels
    Strategy strategy;
    PlantedBug bug;
};

/// Path state, one entry per live path.
struct PathView {
    trav::Ray* ray;
    trav::Hit* hit;
    Vec3* throughput;
    uint32_t* slot;   ///< the path's slot in the pass: its pixel, its sample and its radiance entry
    float* prev_pdf;  ///< the BSDF density that chose ray; 0 for the camera and delta lobes
};

/// What shade leaves at entry i: a continuation (if alive) and a shadow ray (if shadow).
struct ShadeOut {
    trav::Ray* next_ray;
    Vec3* next_throughput;
    float* next_pdf;
    uint8_t* alive;
    trav::Ray* shadow_ray;
    Vec3* shadow_radiance;  ///< added to the slot's radiance when the shadow ray is unoccluded
    uint8_t* shadow;
    Vec3* albedo;  ///< per slot, or null: the first hit's reflectance (for denoisers)
    Vec3* normal;  ///< per slot, or null: the first hit's normal, facing the camera
};

/// The reflectance a denoiser's albedo buffer shows for a material of base colour `base`
/// (textured or not): the base colour of diffuse lobes, the reflectance of specular ones,
/// white for glass.
BVHLAB_HD inline Vec3 material_albedo(const RenderMaterial& m, Vec3 base) {
    switch (m.type) {
        case BsdfType::kMirror:
        case BsdfType::kConductor:
            return m.specular;
        case BsdfType::kGlass:
            return splat(1.0f);
        default:
            return base;
    }
}

/// The base colour at barycentrics (b1, b2) of triangle `tri`: its map_Kd texture when it has
/// one and the mesh has texture coordinates (the texture replaces Kd), else Kd.
BVHLAB_HD inline Vec3 base_colour(const SceneView& s, const RenderMaterial& m, uint32_t tri, float b1, float b2) {
    if (m.texture < 0 || !s.textures.texcoords) return m.base;
    float u, v;
    triangle_texcoords(s.textures.texcoords, tri, b1, b2, u, v);
    return sample_texture(s.textures.texels, s.textures.info[m.texture], u, v);
}

/// The shading normal at barycentrics (b1, b2) of triangle `tri`, whose unit geometric normal is
/// ng: its corners' normals interpolated and normalised, turned to ng's side; ng itself where the
/// mesh has no normals, the triangle's corners have none (zeros), or they cancel out.
BVHLAB_HD inline Vec3 shading_normal(const SceneView& s, uint32_t tri, float b1, float b2, Vec3 ng) {
    if (!s.normals) return ng;
    const Vec3* c = s.normals + 3 * size_t(tri);
    const Vec3 n = c[0] * (1.0f - b1 - b2) + c[1] * b1 + c[2] * b2;
    const float len = length(n);
    if (!(len > 1e-6f)) return ng;
    return n * ((dot(n, ng) < 0.0f ? -1.0f : 1.0f) / len);
}

/// The shading normal ns (unit, on the geometric normal's side) bent by m's normal or height map
/// at barycentrics (b1, b2) of triangle `tri`, in the frame of the triangle's texture
/// coordinates. ns itself where m has no map, the mesh no texture coordinates, or the mapping is
/// degenerate.
BVHLAB_HD inline Vec3 mapped_normal(const SceneView& s, const RenderMaterial& m, uint32_t tri, float b1, float b2,
                                    Vec3 ns) {
    if (m.normal_kind == NormalMapKind::kNone || !s.textures.texcoords) return ns;
    const Vec3 p0 = s.vertices[s.indices[3 * tri]], p1 = s.vertices[s.indices[3 * tri + 1]],
               p2 = s.vertices[s.indices[3 * tri + 2]];
    Vec3 dpdu, dpdv;
    if (!uv_derivatives(p0, p1, p2, s.textures.texcoords + 6 * size_t(tri), dpdu, dpdv)) return ns;
    float u, v;
    triangle_texcoords(s.textures.texcoords, tri, b1, b2, u, v);
    const TextureInfo& t = s.textures.info[m.normal_map];
    if (m.normal_kind == NormalMapKind::kTangentSpace)
        return tangent_space_normal(ns, dpdu, dpdv, sample_texture(s.textures.texels, t, u, v), m.bump_scale);
    float hu, hv;
    height_derivatives(s.textures.texels, t, u, v, m.bump_scale, hu, hv);
    return height_normal(ns, dpdu, dpdv, hu, hv);
}

/// Whether a path that arrives from wo (pointing away from the surface) and leaves along wi
/// crosses the geometric surface as the shading frame says it does: reflection (both on one side
/// of the shading normal n) must stay on one side of ng, transmission must cross it. Shading
/// normals bend the frame; without this guard a reflected ray can leave through the back of the
/// surface, or light from behind a wall leak onto its front.
BVHLAB_HD inline bool consistent_sides(Vec3 ng, Vec3 n, Vec3 wo, Vec3 wi) {
    const bool reflect_shading = (dot(n, wo) > 0.0f) == (dot(n, wi) > 0.0f);
    const bool reflect_geometric = (dot(ng, wo) > 0.0f) == (dot(ng, wi) > 0.0f);
    return reflect_shading == reflect_geometric;
}

BVHLAB_HD inline const RenderMaterial& material_of(const SceneView& s, uint32_t tri) {
    return s.materials[s.material_ids[tri] + 1];
}

BVHLAB_HD inline uint32_t pixel_of(const PathParams& p, uint32_t slot) { return slot % p.pixels; }
BVHLAB_HD inline uint32_t sample_of(const PathParams& p, uint32_t slot) { return p.first_sample + slot / p.pixels; }

/// Stage "generate": slot i's camera ray.
BVHLAB_HD inline void generate_path(uint32_t i, const CameraData& cam, const PathParams& p, PathView paths) {
    trav::store_ray(paths.ray, i, camera_ray(cam, pixel_of(p, i), sample_of(p, i), p.seed));
    paths.throughput[i] = splat(1.0f);
    paths.slot[i] = i;
    paths.prev_pdf[i] = 0.0f;
}

/// A point off the surface of geometric normal ng, on the side that direction d leaves towards.
BVHLAB_HD inline Vec3 offset_point(Vec3 p, Vec3 ng, Vec3 d, float offset) {
    return p + ng * (dot(ng, d) >= 0.0f ? offset : -offset);
}

/// What shading one path leaves: its continuation (if alive) and a shadow ray (if shadow).
struct ShadeResult {
    trav::Ray next_ray;
    Vec3 next_throughput;
    float next_pdf;
    bool alive;
    trav::Ray shadow_ray;
    Vec3 shadow_radiance;
    bool shadow;
};

/// Stage "shade" for path i at bounce `bounce` (0: the camera ray's hit): adds what it sees to
/// radiance[slot] (and, at bounce 0, the first hit to albedo/normal[slot] when not null), and
/// returns the shadow ray for next-event estimation and the continuation. The drivers store
/// the result: the CPU at i (then compacts), the GPU at its compacted position.
BVHLAB_HD inline ShadeResult shade(uint32_t i, uint32_t bounce, const SceneView& s, const PathParams& p, PathView paths,
                                   Vec3* radiance, Vec3* albedo, Vec3* normal) {
    ShadeResult out;
    out.alive = false;
    out.shadow = false;
    const trav::Ray ray = trav::load_ray(paths.ray, i);
    const trav::Hit hit = trav::load_hit(paths.hit, i);
    Vec3 beta = paths.throughput[i];
    const uint32_t px = paths.slot[i];
    const float prev_pdf = paths.prev_pdf[i];
    const bool bsdf_counts = p.strategy != Strategy::kLightOnly || prev_pdf == 0.0f;
    const bool mis = p.strategy == Strategy::kMis && prev_pdf > 0.0f;
    if (!hit.is_hit()) {
        if (bounce == 0 && albedo) albedo[px] = normal[px] = splat(0.0f);
        if (bsdf_counts && has_sky(s.lights)) {
            const float w = mis ? power_heuristic(prev_pdf, sky_direction_pdf(s.lights, ray.dir)) : 1.0f;
            radiance[px] = radiance[px] + beta * sky_radiance(s.lights, ray.dir) * w;
        }
        return out;
    }
    const uint32_t tri = uint32_t(hit.tri);
    const Vec3 v0 = s.vertices[s.indices[3 * tri]], v1 = s.vertices[s.indices[3 * tri + 1]],
               v2 = s.vertices[s.indices[3 * tri + 2]];
    const Vec3 cr = cross(v1 - v0, v2 - v0);
    const float area2 = length(cr);
    const Vec3 ng = cr * (1.0f / area2);
    const Vec3 pos = ray.org + ray.dir * hit.t;
    const RenderMaterial& m = material_of(s, tri);
    const Vec3 base = base_colour(s, m, tri, hit.u, hit.v);
    const Vec3 wo = ray.dir * -1.0f;
    // The shading normal, unless wo sees it from the other side than ng (a grazing view of a
    // strongly bent normal): BSDFs take wo on the frame's side, so ng then.
    Vec3 ns = mapped_normal(s, m, tri, hit.u, hit.v, shading_normal(s, tri, hit.u, hit.v, ng));
    if ((dot(ns, wo) > 0.0f) != (dot(ng, wo) > 0.0f)) ns = ng;
    if (bounce == 0 && albedo) {
        albedo[px] = material_albedo(m, base);
        normal[px] = dot(ns, wo) < 0.0f ? ns * -1.0f : ns;
    }
    Vec3 add = splat(0.0f);
    if (bsdf_counts && max3(m.emission) > 0.0f) {
        float w = 1.0f;
        if (mis && s.lights.pick_pdf[tri] > 0.0f && p.bug != PlantedBug::kBsdfWeightOne) {
            const float cos_l = fabsf(dot(ng, ray.dir));
            w = power_heuristic(prev_pdf, triangle_light_pdf(s.lights, tri, 0.5f * area2, hit.t, cos_l));
        }
        add = beta * m.emission * w;
    }
    radiance[px] = radiance[px] + add;
    if (bounce + 1 >= p.max_depth) return out;

    const bool opaque = m.type != BsdfType::kGlass;
    const Vec3 n = opaque && dot(ns, wo) < 0.0f ? ns * -1.0f : ns;
    // Without shading normals or a normal map n is ±ng and the sides always agree: the guard is skipped.
    const bool bent = s.normals != nullptr || m.normal_kind != NormalMapKind::kNone;
    const Frame frame = Frame::around(n);
    const Vec3 wo_l = frame.to_local(wo);
    const uint32_t pixel = pixel_of(p, px), sample = sample_of(p, px);
    auto rnd = [&](uint32_t d) { return rand01(pixel, sample, bounce_dim(bounce, d), p.seed); };

    // Next-event estimation, for every lobe that is not a delta.
    const bool smooth = m.type == BsdfType::kMirror || m.type == BsdfType::kGlass;
    const bool has_lights = s.lights.count > 0 || s.lights.sky_pick > 0.0f;
    if (!smooth && has_lights && p.strategy != Strategy::kBsdfOnly) {
        const float u = rnd(kDimLightPick);
        Vec3 dir, le;
        float dist, pdf_l;
        if (u < s.lights.sky_pick) {
            if (s.lights.env.present()) {
                float pdf_env;
                dir = env_sample(s.lights.env, rnd(kDimLight0), rnd(kDimLight1), pdf_env);
                pdf_l = s.lights.sky_pick * pdf_env;
            } else {
                dir = sample_uniform_sphere(rnd(kDimLight0), rnd(kDimLight1));
                pdf_l = sky_direction_pdf(s.lights, dir);
            }
            dist = INFINITY;
            le = sky_radiance(s.lights, dir);
        } else {
            const float ul = (u - s.lights.sky_pick) / (1.0f - s.lights.sky_pick);
            const uint32_t lt = s.lights.tris[alias_pick(s.lights.table, s.lights.count, min_f(ul, 0.99999994f))];
            const Vec3 a = s.vertices[s.indices[3 * lt]], b = s.vertices[s.indices[3 * lt + 1]],
                       c = s.vertices[s.indices[3 * lt + 2]];
            float b1, b2;
            sample_triangle(rnd(kDimLight0), rnd(kDimLight1), b1, b2);
            const Vec3 q = a * (1.0f - b1 - b2) + b * b1 + c * b2;
            const Vec3 lc = cross(b - a, c - a);
            const float larea2 = length(lc);
            dir = q - pos;
            dist = length(dir);
            dir = dir * (1.0f / dist);
            const float cos_l = fabsf(dot(lc, dir)) / larea2;
            pdf_l = cos_l > 0.0f ? triangle_light_pdf(s.lights, lt, 0.5f * larea2, dist, cos_l) : 0.0f;
            le = material_of(s, lt).emission;
        }
        float pdf_b = 0.0f;
        const Vec3 wi_l = frame.to_local(dir);
        Vec3 fcos = (!bent || consistent_sides(ng, n, wo, dir)) ? eval_bsdf(m, base, wo_l, wi_l, pdf_b) : splat(0.0f);
        if (p.bug == PlantedBug::kNoCosine && wi_l.z > 0.0f) fcos = fcos * (1.0f / wi_l.z);
        if (pdf_l > 0.0f && max3(fcos) > 0.0f) {
            const float w = p.strategy == Strategy::kMis ? power_heuristic(pdf_l, pdf_b) : 1.0f;
            const Vec3 org = offset_point(pos, ng, dir, s.offset);
            // Stop short of the light's own triangle: 1e-4 of the distance.
            out.shadow_ray = {org, 0.0f, dir, dist < INFINITY ? dist * (1.0f - 1e-4f) : INFINITY};
            out.shadow_radiance = beta * fcos * le * (w / pdf_l);
            out.shadow = true;
        }
    }

    // The continuation, by BSDF sampling.
    BsdfSample bs;
    if (!sample_bsdf(m, base, wo_l, rnd(kDimBsdfLobe), rnd(kDimBsdf0), rnd(kDimBsdf1), bs)) return out;
    beta = beta * bs.weight;
    if (bounce + 1 >= p.rr_depth) {
        const float q = min_f(0.95f, max3(beta));
        if (!(rnd(kDimRoulette) < q)) return out;
        beta = beta * (1.0f / q);
    }
    const Vec3 dir = normalize(frame.to_world(bs.wi));
    if (bent && !consistent_sides(ng, n, wo, dir)) return out;
    out.next_ray = {offset_point(pos, ng, dir, s.offset), 0.0f, dir, INFINITY};
    out.next_throughput = beta;
    out.next_pdf = bs.delta ? 0.0f : bs.pdf;
    out.alive = true;
    return out;
}

/// shade() with the result stored at entry i of `out` (the CPU driver, which compacts after).
BVHLAB_HD inline void shade_path(uint32_t i, uint32_t bounce, const SceneView& s, const PathParams& p, PathView paths,
                                 ShadeOut out, Vec3* radiance) {
    const ShadeResult r = shade(i, bounce, s, p, paths, radiance, out.albedo, out.normal);
    out.alive[i] = r.alive;
    out.shadow[i] = r.shadow;
    if (r.alive) {
        trav::store_ray(out.next_ray, i, r.next_ray);
        out.next_throughput[i] = r.next_throughput;
        out.next_pdf[i] = r.next_pdf;
    }
    if (r.shadow) {
        trav::store_ray(out.shadow_ray, i, r.shadow_ray);
        out.shadow_radiance[i] = r.shadow_radiance;
    }
}

/// Stage "shadow": adds an unoccluded shadow ray's radiance to its slot.
BVHLAB_HD inline void resolve_shadow(uint32_t i, const trav::Hit* occlusion, const uint32_t* slot,
                                     const Vec3* shadow_radiance, Vec3* radiance) {
    if (!occlusion[i].is_hit()) radiance[slot[i]] = radiance[slot[i]] + shadow_radiance[i];
}

/// Per-pixel sums the accumulate stage adds the pass's slots into.
struct PixelSums {
    Vec3* sum;
    Vec3* sum_sq;
    Vec3* albedo;  ///< null when no albedo or normal buffers were asked for
    Vec3* normal;
};

/// Stage "accumulate": folds pixel px's `samples` slots of the pass (radiance, and the per-slot
/// albedo and normal when out.albedo is set) into its sums (the sum of squares gives the
/// variance the image comparisons use), and clears the radiance slots.
BVHLAB_HD inline void accumulate_pixel(uint32_t px, uint32_t pixels, uint32_t samples, Vec3* radiance,
                                       const Vec3* albedo, const Vec3* normal, PixelSums out) {
    Vec3 s1 = out.sum[px], s2 = out.sum_sq[px];
    for (uint32_t k = 0; k < samples; ++k) {
        const size_t slot = size_t(k) * pixels + px;
        Vec3& r = radiance[slot];
        s1 = s1 + r;
        s2 = s2 + r * r;
        r = splat(0.0f);
        if (out.albedo) {
            out.albedo[px] = out.albedo[px] + albedo[slot];
            out.normal[px] = out.normal[px] + normal[slot];
        }
    }
    out.sum[px] = s1;
    out.sum_sq[px] = s2;
}

}  // namespace bvhlab::render
