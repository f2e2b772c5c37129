// SPDX-License-Identifier: MIT
// Loads an OBJ, builds an SBVH with the library's factory, traces camera rays and diffuse
// rays on the CPU (and on the GPU when there is one), checks every hit against Embree, and
// prints the figures. Usage: trace_scene SCENE.obj [builder] [layout]
#include <chrono>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include <bvhlab/accel/core/check.h>
#include <bvhlab/scene/io/obj_loader.h>
#include <bvhlab/traversal/factory.h>
#include <bvhlab/traversal/oracle/compare.h>
#include <bvhlab/traversal/oracle/embree_oracle.h>
#include <bvhlab/traversal/rays/protocol.h>

using namespace bvhlab;

namespace {

/// Traces `set` with `tracer`, compares with Embree, prints one line; returns the real mismatches.
size_t trace_and_check(trav::Tracer& tracer, const scene::TriangleMesh& mesh, const trav::EmbreeOracle& oracle,
                       const trav::RaySet& set, const char* what) {
    tracer.set_rays(set.rays, set.query);
    tracer.run();  // warm-up (a GPU tracer's first launch loads the module)
    const double ms = tracer.run();
    std::vector<trav::Hit> ours, ref;
    tracer.hits(ours);
    oracle.trace(set.rays, set.query, ref);
    const trav::CompareReport rep = trav::compare_hits(mesh, set.rays, set.query, ours, ref,
                                                       [&](const trav::Ray& r) { return oracle.intersect(r); });
    std::printf("%-8s %-26s %9zu rays %9.1f Mrays/s  agree %zu, ties %zu, mismatches %zu\n", what,
                tracer.name().c_str(), set.rays.size(), ms > 0 ? double(set.rays.size()) / (ms * 1e3) : 0.0, rep.agree,
                rep.ties, rep.mismatches);
    return rep.mismatches;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: %s SCENE.obj [builder: binned|sweep|sbvh|kdtree] [layout: bvh2|cwbvh]\n", argv[0]);
        return 2;
    }
    try {
        const scene::TriangleMesh mesh = scene::load_obj(argv[1]);
        trav::StructureSpec spec;
        spec.builder = argc > 2 ? argv[2] : "sbvh";
        spec.layout = argc > 3 ? argv[3] : "bvh2";
        trav::AccelStructure s = trav::build_structure(mesh, spec);
        std::printf("%s over %zu triangles: %s nodes, SAH %.3f, %.1f ms\n", s.structure.name.c_str(),
                    mesh.triangle_count(), s.figures["nodes"].dump().c_str(), s.stats.sah, s.result.build_ms);

        trav::EmbreeOracle oracle(mesh);
        trav::ProtocolConfig cfg;
        cfg.camera = trav::framing_camera(mesh);
        cfg.primary.width = 640;
        cfg.primary.height = 480;
        trav::RayProtocol protocol(mesh, oracle, cfg);
        const trav::RaySet primary = protocol.make(trav::RayType::kPrimary);
        const trav::RaySet diffuse = protocol.make(trav::RayType::kDiffuse);

        size_t mismatches = 0;
        auto cpu = s.cpu_tracer();
        mismatches += trace_and_check(*cpu, mesh, oracle, primary, "primary");
        mismatches += trace_and_check(*cpu, mesh, oracle, diffuse, "diffuse");
        std::string why;
        if (trav::gpu_available(&why)) {
            auto gpu = s.gpu_tracer();  // the registry's default kernel for the layout
            mismatches += trace_and_check(*gpu, mesh, oracle, primary, "primary");
            mismatches += trace_and_check(*gpu, mesh, oracle, diffuse, "diffuse");
        } else {
            std::printf("no GPU: %s\n", why.c_str());
        }
        std::printf("%s\n", mismatches ? "FAILED: real mismatches against Embree" : "every hit agrees with Embree");
        return mismatches ? 1 : 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "trace_scene: %s\n", e.what());
        return 1;
    }
}
