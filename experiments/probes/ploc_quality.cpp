// SPDX-License-Identifier: MIT
// Probe: SAH and EPO of the CPU references of the GPU builders' hierarchies (LBVH, PLOC with
// several radii), with the GPU builders' leaf choice, beside the binned SAH build of the same
// scene, and the CPU tracer's node visits and triangle tests per ray (framing camera, primary
// and diffuse rays); with REINSERT=n also each tree after n passes of subtree reinsertion
// (accel::optimize_by_reinsertion), the lead for an optimiser after the GPU builds.
// Usage: [MAX_LEAF=n] [BITS=30|60] [REINSERT=n] ploc_quality SCENE.obj|soup [radius ...]
#include <cstdlib>
#include <string>
#include <vector>

#include "accel/builders/builder.h"
#include "accel/builders/lbvh_reference.h"
#include "accel/builders/reinsertion.h"
#include "probe_trees.h"
#include "traversal/factory.h"

using namespace bvhlab;

static probe::RaySets g_rays;

static void report(const char* name, accel::BuildTree t, const scene::TriangleMesh& m, const accel::BuildConfig& c) {
    probe::print_tree(name, 12, t, m, c, g_rays);
    if (const char* e = std::getenv("REINSERT")) {
        accel::optimize_by_reinsertion(t, c, std::atoi(e));
        probe::print_tree(std::string(name) + " +reins", 12, t, m, c, g_rays);
    }
}

int main(int argc, char** argv) {
    if (argc < 2) return 2;
    const scene::TriangleMesh mesh = probe::load_mesh(argv[1]);
    g_rays = probe::framing_rays(mesh);
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
