// SPDX-License-Identifier: MIT
// Probe: SAH and EPO of the CPU references of the GPU builders' hierarchies (LBVH, PLOC with
// several radii), with the GPU builders' leaf choice, beside the binned SAH build of the same
// scene, and the CPU tracer's node visits and triangle tests per ray (framing camera, primary
// and diffuse rays); with REINSERT=n also each tree after n passes of subtree reinsertion
// (accel::optimize_by_reinsertion), the lead for an optimiser after the GPU builds.
// Usage: [MAX_LEAF=n] [BITS=30|60] [REINSERT=n] ploc_quality SCENE.obj|soup [radius ...]
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "accel/builders/builder.h"
#include "accel/builders/lbvh_reference.h"
#include "accel/builders/reinsertion.h"
#include "accel/core/stats.h"
#include "accel/layouts/bvh2_convert.h"
#include "scene/io/obj_loader.h"
#include "scene/io/procedural.h"
#include "traversal/cpu/cpu_trace.h"
#include "traversal/factory.h"
#include "traversal/oracle/embree_oracle.h"
#include "traversal/rays/protocol.h"
#include "traversal/rays/raygen.h"

using namespace bvhlab;

static std::vector<std::pair<std::string, trav::RaySet>> g_rays;

static void report_one(const char* name, const accel::BuildTree& t, const scene::TriangleMesh& m,
                       const accel::BuildConfig& c);

static void report(const char* name, accel::BuildTree t, const scene::TriangleMesh& m, const accel::BuildConfig& c) {
    report_one(name, t, m, c);
    if (const char* e = std::getenv("REINSERT")) {
        accel::optimize_by_reinsertion(t, c, std::atoi(e));
        report_one((std::string(name) + " +reins").c_str(), t, m, c);
    }
}

static void report_one(const char* name, const accel::BuildTree& t, const scene::TriangleMesh& m,
                       const accel::BuildConfig& c) {
    const accel::TreeStats s = accel::compute_stats(t, m, c);
    std::printf("%-12s SAH %8.3f EPO %7.3f nodes %6zu", name, s.sah, s.epo, t.nodes.size());
    const accel::Bvh2 bvh = accel::convert_to_bvh2(t, m);
    for (const auto& [type, set] : g_rays) {
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
}

int main(int argc, char** argv) {
    if (argc < 2) return 2;
    const std::string path = argv[1];
    scene::TriangleMesh mesh = path == "soup" ? scene::make_procedural(scene::parse_procedural_kind("soup"), 100000, 1)
                                              : scene::load_obj(path);
    {
        const trav::EmbreeOracle oracle(mesh);
        trav::ProtocolConfig cfg;
        cfg.camera = trav::framing_camera(mesh);
        cfg.primary = {256, 192, 1, 0};
        trav::RayProtocol proto(mesh, oracle, cfg);
        g_rays.emplace_back("primary", proto.make(trav::RayType::kPrimary));
        g_rays.emplace_back("diffuse", proto.make(trav::RayType::kDiffuse));
    }
    accel::BuildConfig c;
    if (const char* e = std::getenv("MAX_LEAF")) c.max_leaf_size = uint32_t(std::atoi(e));
    trav::StructureSpec spec;
    spec.builder = "binned";
    spec.options.config.max_leaf_size = c.max_leaf_size;
    report("binned", accel::run_builder(accel::BuilderKind::kBinned, mesh, spec.options).tree, mesh, c);
    report("lbvh30", accel::tree_from_hierarchy(accel::lbvh_reference(mesh, 30), c), mesh, c);
    std::vector<int> radii;
    for (int i = 2; i < argc; ++i) radii.push_back(std::atoi(argv[i]));
    if (radii.empty()) radii = {1, 4, 8, 16};
    for (int r : radii) {
        const int bits = std::getenv("BITS") ? std::atoi(std::getenv("BITS")) : 30;
        const std::string name = "ploc" + std::to_string(bits) + " r" + std::to_string(r);
        report(name.c_str(), accel::tree_from_hierarchy(accel::ploc_reference(mesh, bits, r), c), mesh, c);
    }
}
