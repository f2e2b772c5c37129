// SPDX-License-Identifier: MIT
// What the tree-quality probes (ploc_quality, hybrid_quality) share: the scene, the framing
// camera's primary and diffuse rays, and one line per tree with its SAH, EPO, node count and the
// CPU tracer's node visits and triangle tests per ray.
#pragma once

#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "accel/core/build_tree.h"
#include "accel/core/stats.h"
#include "accel/layouts/bvh2_convert.h"
#include "scene/io/obj_loader.h"
#include "scene/io/procedural.h"
#include "traversal/cpu/cpu_trace.h"
#include "traversal/oracle/embree_oracle.h"
#include "traversal/rays/protocol.h"
#include "traversal/rays/raygen.h"

namespace bvhlab::probe {

using RaySets = std::vector<std::pair<std::string, trav::RaySet>>;

/// An OBJ file, or "soup": the 100k-triangle generated soup (seed 1).
inline scene::TriangleMesh load_mesh(const std::string& path) {
    return path == "soup" ? scene::make_procedural(scene::parse_procedural_kind("soup"), 100000, 1)
                          : scene::load_obj(path);
}

/// The protocol's primary (256 x 192) and diffuse rays from the framing camera of `mesh`.
inline RaySets framing_rays(const scene::TriangleMesh& mesh) {
    const trav::EmbreeOracle oracle(mesh);
    trav::ProtocolConfig cfg;
    cfg.camera = trav::framing_camera(mesh);
    cfg.primary = {256, 192, 1, 0};
    trav::RayProtocol proto(mesh, oracle, cfg);
    RaySets sets;
    sets.emplace_back("primary", proto.make(trav::RayType::kPrimary));
    sets.emplace_back("diffuse", proto.make(trav::RayType::kDiffuse));
    return sets;
}

/// One line: `name` padded to `width`, the tree's SAH, EPO and nodes, then per ray set the mean
/// node visits and triangle tests of a ray.
inline void print_tree(const std::string& name, int width, const accel::BuildTree& t, const scene::TriangleMesh& m,
                       const accel::BuildConfig& c, const RaySets& rays) {
    const accel::TreeStats s = accel::compute_stats(t, m, c);
    std::printf("%-*s SAH %8.3f EPO %7.3f nodes %8zu", width, name.c_str(), s.sah, s.epo, t.nodes.size());
    const accel::Bvh2 bvh = accel::convert_to_bvh2(t, m);
    for (const auto& [type, set] : rays) {
        std::vector<trav::Hit> h;
        std::vector<trav::TraversalCounters> k;
        trav::trace_cpu(bvh, set.rays, set.query, h, &k);
        double nodes = 0, tris = 0;
        for (const auto& x : k) {
            nodes += double(x.nodes);
            tris += double(x.tri_tests);
        }
        std::printf("  %s nodes %.1f tris %.1f", type.c_str(), nodes / double(k.size()), tris / double(k.size()));
    }
    std::printf("\n");
    std::fflush(stdout);
}

}  // namespace bvhlab::probe
