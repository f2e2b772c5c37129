// SPDX-License-Identifier: MIT
// BSDFs in a local frame (z = the shading normal), host and device code written once. Every
// function returns f * |cos(theta_i)|, so that a sample's weight is that over its pdf.
// Conventions: wo points away from the surface towards the previous vertex, wi towards the
// next; both are unit vectors. Opaque BSDFs are evaluated with wo on the +z side (the caller
// flips the frame); glass keeps the frame's orientation to know inside from outside (+z is the
// outside, where the triangle's geometric normal points).
#pragma once

#include "renderer/core/material.h"
#include "renderer/core/sampling.h"

namespace bvhlab::render {

struct BsdfSample {
    Vec3 wi;
    Vec3 weight;  ///< f |cos| / pdf (for a delta lobe: the lobe's reflectance or transmittance)
    float pdf;    ///< solid-angle density; 0 for a delta lobe
    bool delta;
};

/// Fresnel reflectance of a smooth dielectric interface. cos_i > 0 measures from the side the
/// light arrives on; eta = n_t / n_i. Returns 1 under total internal reflection.
BVHLAB_HD inline float fresnel_dielectric(float cos_i, float eta) {
    const float sin2_t = (1.0f - cos_i * cos_i) / (eta * eta);
    if (sin2_t >= 1.0f) return 1.0f;
    const float cos_t = sqrtf(1.0f - sin2_t);
    const float rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    const float rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    return 0.5f * (rs * rs + rp * rp);
}

BVHLAB_HD inline Vec3 fresnel_schlick(Vec3 f0, float cos_i) {
    const float m = 1.0f - max_f(0.0f, min_f(1.0f, cos_i));
    const float m5 = m * m * m * m * m;
    return f0 + (splat(1.0f) - f0) * m5;
}

// --- GGX (Trowbridge-Reitz), isotropic, with Smith's height-correlated masking-shadowing.

BVHLAB_HD inline float ggx_d(Vec3 h, float alpha) {
    const float a2 = alpha * alpha;
    const float t = h.z * h.z * (a2 - 1.0f) + 1.0f;
    return a2 / (kPi * t * t);
}
BVHLAB_HD inline float ggx_lambda(Vec3 w, float alpha) {
    const float z2 = w.z * w.z;
    if (z2 <= 0.0f) return 0.0f;
    const float tan2 = max_f(0.0f, 1.0f - z2) / z2;
    return 0.5f * (-1.0f + sqrtf(1.0f + alpha * alpha * tan2));
}
BVHLAB_HD inline float ggx_g1(Vec3 w, float alpha) { return 1.0f / (1.0f + ggx_lambda(w, alpha)); }
BVHLAB_HD inline float ggx_g2(Vec3 wo, Vec3 wi, float alpha) {
    return 1.0f / (1.0f + ggx_lambda(wo, alpha) + ggx_lambda(wi, alpha));
}

/// A visible normal for wo (wo.z > 0): Heitz, "Sampling the GGX distribution of visible
/// normals", JCGT 2018. Its density is G1(wo) max(0, wo.h) D(h) / wo.z.
BVHLAB_HD inline Vec3 ggx_sample_visible_normal(Vec3 wo, float alpha, float u0, float u1) {
    const Vec3 vh = normalize(Vec3{alpha * wo.x, alpha * wo.y, wo.z});
    const float len2 = vh.x * vh.x + vh.y * vh.y;
    const Vec3 t1 = len2 > 0.0f ? Vec3{-vh.y, vh.x, 0.0f} * (1.0f / sqrtf(len2)) : Vec3{1.0f, 0.0f, 0.0f};
    const Vec3 t2 = cross(vh, t1);
    const float r = sqrtf(u0);
    const float phi = 2.0f * kPi * u1;
    const float p1 = r * cosf(phi);
    float p2 = r * sinf(phi);
    const float s = 0.5f * (1.0f + vh.z);
    p2 = (1.0f - s) * sqrtf(max_f(0.0f, 1.0f - p1 * p1)) + s * p2;
    const Vec3 nh = t1 * p1 + t2 * p2 + vh * sqrtf(max_f(0.0f, 1.0f - p1 * p1 - p2 * p2));
    return normalize(Vec3{alpha * nh.x, alpha * nh.y, max_f(1e-6f, nh.z)});
}

BVHLAB_HD inline Vec3 reflect(Vec3 w, Vec3 h) { return h * (2.0f * dot(w, h)) - w; }

/// Density of reflecting wo into wi about their half vector, by visible-normal sampling.
BVHLAB_HD inline float ggx_reflection_pdf(Vec3 wo, Vec3 wi, float alpha) {
    if (wo.z <= 0.0f || wi.z <= 0.0f) return 0.0f;
    const Vec3 h = normalize(wo + wi);
    return ggx_g1(wo, alpha) * ggx_d(h, alpha) / (4.0f * wo.z);
}

/// The plastic's probability of sampling its coat rather than its base.
BVHLAB_HD inline float plastic_coat_probability(const RenderMaterial& m, Vec3 wo) {
    const float f = fresnel_dielectric(wo.z, m.ior);
    return min_f(0.9f, max_f(0.1f, f));
}

/// f |cos theta_i| of the non-delta lobes for wo, wi in the local frame, and the density with
/// which sample_bsdf() would pick wi. Delta lobes (mirror, glass) give 0 and pdf 0.
BVHLAB_HD inline Vec3 eval_bsdf(const RenderMaterial& m, Vec3 base, Vec3 wo, Vec3 wi, float& pdf) {
    pdf = 0.0f;
    if (wo.z <= 0.0f || wi.z <= 0.0f) return splat(0.0f);
    switch (m.type) {
        case BsdfType::kLambert:
            pdf = wi.z * kInvPi;
            return base * (wi.z * kInvPi);
        case BsdfType::kConductor: {
            const Vec3 h = normalize(wo + wi);
            pdf = ggx_reflection_pdf(wo, wi, m.alpha);
            const float s = ggx_d(h, m.alpha) * ggx_g2(wo, wi, m.alpha) / (4.0f * wo.z);
            return fresnel_schlick(m.specular, dot(wo, h)) * s;
        }
        case BsdfType::kPlastic: {
            const Vec3 h = normalize(wo + wi);
            const float p = plastic_coat_probability(m, wo);
            pdf = p * ggx_reflection_pdf(wo, wi, m.alpha) + (1.0f - p) * wi.z * kInvPi;
            const float coat =
                fresnel_dielectric(dot(wo, h), m.ior) * ggx_d(h, m.alpha) * ggx_g2(wo, wi, m.alpha) / (4.0f * wo.z);
            const float through = (1.0f - fresnel_dielectric(wo.z, m.ior)) * (1.0f - fresnel_dielectric(wi.z, m.ior));
            return splat(coat) + base * (through * wi.z * kInvPi);
        }
        default:
            return splat(0.0f);
    }
}

/// Samples wi for wo (local frame) with three uniform numbers; false when the sample carries
/// nothing (below the surface, or a zero density).
BVHLAB_HD inline bool sample_bsdf(const RenderMaterial& m, Vec3 base, Vec3 wo, float u_lobe, float u0, float u1,
                                  BsdfSample& s) {
    s.delta = false;
    s.pdf = 0.0f;
    switch (m.type) {
        case BsdfType::kMirror:
            if (wo.z <= 0.0f) return false;
            s.wi = {-wo.x, -wo.y, wo.z};
            s.weight = m.specular;
            s.delta = true;
            return true;
        case BsdfType::kGlass: {
            const bool entering = wo.z > 0.0f;
            const float eta = entering ? m.ior : 1.0f / m.ior;  // n_t / n_i
            const float cos_o = fabsf(wo.z);
            const float f = fresnel_dielectric(cos_o, eta);
            s.delta = true;
            if (u_lobe < f) {
                s.wi = {-wo.x, -wo.y, wo.z};
                s.weight = splat(1.0f);
                return true;
            }
            const float sin2_t = (1.0f - cos_o * cos_o) / (eta * eta);
            const float cos_t = sqrtf(max_f(0.0f, 1.0f - sin2_t));
            // Refraction bends about the normal on wo's side; radiance scales by 1 / eta^2.
            const float side = entering ? 1.0f : -1.0f;
            s.wi = Vec3{-wo.x / eta, -wo.y / eta, -side * cos_t};
            s.weight = splat(1.0f / (eta * eta));
            return true;
        }
        case BsdfType::kLambert:
            if (wo.z <= 0.0f) return false;
            s.wi = sample_cosine_hemisphere(u0, u1);
            break;
        case BsdfType::kConductor: {
            if (wo.z <= 0.0f) return false;
            s.wi = reflect(wo, ggx_sample_visible_normal(wo, m.alpha, u0, u1));
            break;
        }
        case BsdfType::kPlastic: {
            if (wo.z <= 0.0f) return false;
            if (u_lobe < plastic_coat_probability(m, wo))
                s.wi = reflect(wo, ggx_sample_visible_normal(wo, m.alpha, u0, u1));
            else
                s.wi = sample_cosine_hemisphere(u0, u1);
            break;
        }
    }
    const Vec3 f = eval_bsdf(m, base, wo, s.wi, s.pdf);
    if (!(s.pdf > 0.0f)) return false;
    s.weight = f * (1.0f / s.pdf);
    return true;
}

}  // namespace bvhlab::render
