// SPDX-License-Identifier: MIT
// A surface material as a scene file gives it; the renderer maps it to a BSDF
// (renderer/core/material.h). The acceleration structures never read it.
#pragma once

#include <cstdint>
#include <string>

#include "accel/core/vec3.h"

namespace bvhlab::scene {

/// A material as the OBJ's MTL file gives it: the parameters the renderer maps to a BSDF
/// (renderer/core/material.h says how). A loaded material has tinyobjloader's values for
/// absent keys (Kd 0, Ns 1, Ni 1, d 1, illum 0); the defaults below are for made-up materials.
struct Material {
    std::string name;
    Vec3 diffuse{0.8f, 0.8f, 0.8f};   ///< Kd
    Vec3 emission{0.0f, 0.0f, 0.0f};  ///< Ke
    Vec3 specular{0.0f, 0.0f, 0.0f};  ///< Ks
    Vec3 ambient{0.0f, 0.0f, 0.0f};   ///< Ka (read as emission when above 1 and Ke is black)
    float shininess = 1.0f;           ///< Ns (Phong exponent)
    float ior = 1.0f;                 ///< Ni
    float dissolve = 1.0f;            ///< d (1 - Tr)
    int32_t illum = 0;                ///< illumination model
    std::string diffuse_texture;      ///< map_Kd as written in the MTL, backslashes included
    std::string normal_texture;       ///< norm (glTF normalTexture): a tangent-space normal map
    std::string bump_texture;         ///< map_Bump / bump: a height map, or a normal map (by content)
    float bump_multiplier = 1.0f;     ///< -bm of bump/norm (glTF's normalTexture.scale)
};

}  // namespace bvhlab::scene
