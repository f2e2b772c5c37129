// SPDX-License-Identifier: MIT
// The renderer's material: one BSDF per triangle's material, mapped from the MTL parameters.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "accel/core/hd.h"
#include "accel/core/vec3.h"
#include "scene/mesh.h"

namespace bvhlab::render {

enum class BsdfType : uint32_t {
    kLambert = 0,    ///< Kd / pi
    kMirror = 1,     ///< perfect specular reflection, reflectance Ks
    kGlass = 2,      ///< smooth dielectric of index Ni: exact Fresnel, reflect or refract
    kConductor = 3,  ///< GGX microfacets, Schlick Fresnel with F0 = Ks
    kPlastic = 4,    ///< a GGX dielectric coat of index Ni over a Lambertian Kd base
};

/// How a material's normal_map texture bends the shading normal (renderer/core/normal_map.h).
enum class NormalMapKind : uint32_t {
    kNone = 0,
    kTangentSpace = 1,  ///< texels are (n + 1) / 2 of a unit normal in the (tangent, bitangent, normal) frame
    kHeight = 2,        ///< texels are heights (their mean), in scene units times bump_scale
};

/// One material as both integrators read it, 64 bytes.
struct RenderMaterial {
    Vec3 base;           ///< Kd: the Lambertian or plastic base colour
    BsdfType type;       //
    Vec3 specular;       ///< Ks: mirror and conductor reflectance (F0)
    float alpha;         ///< GGX roughness, from Ns
    Vec3 emission;       ///< Ke: radiance leaving either side of the triangle
    float ior;           ///< Ni (glass and plastic)
    int32_t texture;     ///< index into the scene's textures for map_Kd, -1 for none
    int32_t normal_map;  ///< index into the scene's textures for the normal or height map, -1 for none
    NormalMapKind normal_kind;
    float bump_scale;  ///< -bm: scales a normal map's tangent-plane part, or a height map's heights
};
static_assert(sizeof(RenderMaterial) == 64, "RenderMaterial is 64 bytes");

/// The material of triangles without one: grey Lambertian of albedo 0.8 (the Material default).
RenderMaterial default_material();

/// GGX roughness for a Phong exponent: alpha = sqrt(2 / (Ns + 2)), the Beckmann-Phong
/// correspondence of Walter et al. 2007, clamped to [0.001, 1].
float roughness_from_shininess(float ns);

/// The MTL-to-BSDF mapping, in this order (the README's table):
///   d < 1, or illum 4, 6, 7 or 9     -> glass of index Ni (1.5 when Ni <= 1)
///   illum 3 or 5 and Ns >= 1000      -> mirror with reflectance Ks (Kd when Ks is black)
///   illum 3 or 5                     -> rough conductor, F0 = Ks (Kd when Ks is black)
///   illum 2 and Ks not black         -> plastic: Kd base, GGX coat of index Ni (1.5 when <= 1)
///   anything else                    -> Lambertian Kd
/// Ke, when not black, makes the triangle an area light whatever its BSDF; when Ke is black, a
/// Ka above 1 in any channel is read as Ke (tinyobjloader's Cornell box writes its light that
/// way; no reflectance exceeds 1). Emission leaves both sides of the triangle. `texture` is the
/// index the caller gave map_Kd, or -1. The normal map is none; RenderScene sets it.
RenderMaterial map_material(const scene::Material& m, int32_t texture);

}  // namespace bvhlab::render
