// SPDX-License-Identifier: MIT
// The benchmark ray protocol (ray_protocol in scenes.json): primary rays from the scene's
// camera, then AO, diffuse and shadow rays spawned from the primary hits found by Embree.
#pragma once

#include <optional>
#include <string>

#include "scene/mesh.h"
#include "traversal/oracle/embree_oracle.h"
#include "traversal/rays/ray_file.h"
#include "traversal/rays/raygen.h"

namespace bvhlab::trav {

enum class RayType { kPrimary = 0, kAo = 1, kDiffuse = 2, kShadow = 3 };

/// "primary", "ao", "diffuse" or "shadow"; throws bvhlab::Error otherwise.
RayType parse_ray_type(const std::string& name);
const char* ray_type_name(RayType type);
Query ray_type_query(RayType type);

struct ProtocolConfig {
    Camera camera;
    PrimaryConfig primary;
    uint32_t ao_rays = 8;       ///< per primary hit
    uint32_t diffuse_rays = 4;  ///< per primary hit
    float ao_length = 0.0f;     ///< 0: 5% of the scene diagonal
    float offset_rel = 1e-4f;   ///< origin offset as a fraction of the diagonal
    float light_raise = 0.25f;  ///< point light: the eye raised along `up` by this x diagonal
    uint64_t seed = 1;
};

/// Generates the protocol's ray sets on demand; primary hits are traced once (by Embree, so
/// the rays do not depend on the structure under test) and shared by the secondary types.
class RayProtocol {
public:
    RayProtocol(const scene::TriangleMesh& mesh, const EmbreeOracle& oracle, const ProtocolConfig& cfg);
    RaySet make(RayType type);

private:
    const scene::TriangleMesh& mesh_;
    const EmbreeOracle& oracle_;
    ProtocolConfig cfg_;
    float diagonal_;
    std::vector<Ray> primary_;
    std::optional<std::vector<Hit>> primary_hits_;
};

}  // namespace bvhlab::trav
