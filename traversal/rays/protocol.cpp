// SPDX-License-Identifier: MIT
#include "traversal/rays/protocol.h"

#include <glm/geometric.hpp>

#include "accel/core/check.h"

namespace bvhlab::trav {

RayType parse_ray_type(const std::string& name) {
    if (name == "primary") return RayType::kPrimary;
    if (name == "ao") return RayType::kAo;
    if (name == "diffuse") return RayType::kDiffuse;
    if (name == "shadow") return RayType::kShadow;
    throw Error("unknown ray type '" + name + "' (expected primary, ao, diffuse or shadow)");
}

const char* ray_type_name(RayType type) {
    static const char* names[] = {"primary", "ao", "diffuse", "shadow"};
    return names[int(type)];
}

Query ray_type_query(RayType type) {
    return (type == RayType::kAo || type == RayType::kShadow) ? Query::kAny : Query::kClosest;
}

RayProtocol::RayProtocol(const scene::TriangleMesh& mesh, const EmbreeOracle& oracle, const ProtocolConfig& cfg)
    : mesh_(mesh), oracle_(oracle), cfg_(cfg), diagonal_(mesh.diagonal()) {
    primary_ = generate_primary(cfg_.camera, cfg_.primary);
}

RaySet RayProtocol::make(RayType type) {
    RaySet set;
    set.query = ray_type_query(type);
    if (type == RayType::kPrimary) {
        set.rays = primary_;
        return set;
    }
    if (!primary_hits_) {
        primary_hits_.emplace();
        oracle_.trace(primary_, Query::kClosest, *primary_hits_);
    }
    SecondaryConfig sc;
    sc.offset = cfg_.offset_rel * diagonal_;
    sc.seed = cfg_.seed;
    if (type == RayType::kShadow) {
        const glm::vec3 up = glm::normalize(cfg_.camera.up);
        const glm::vec3 light = cfg_.camera.eye + up * (cfg_.light_raise * diagonal_);
        set.rays = generate_shadow(mesh_, primary_, *primary_hits_, {light.x, light.y, light.z}, sc.offset);
        return set;
    }
    sc.per_hit = type == RayType::kAo ? cfg_.ao_rays : cfg_.diffuse_rays;
    sc.tmax = cfg_.ao_length > 0.0f ? cfg_.ao_length : 0.05f * diagonal_;
    set.rays = type == RayType::kAo ? generate_ao(mesh_, primary_, *primary_hits_, sc)
                                    : generate_diffuse(mesh_, primary_, *primary_hits_, sc);
    return set;
}

}  // namespace bvhlab::trav
