// SPDX-License-Identifier: MIT
// The builders alone (bvhlab::accel): a generated scene, a binned SAH BVH and an SBVH, their
// SAH. Needs TBB and nothing else of bvhlab's dependencies.
#include <cstdio>
#include <exception>

#include <bvhlab/accel/builders/builder.h>
#include <bvhlab/accel/core/stats.h>
#include <bvhlab/scene/io/procedural.h>

using namespace bvhlab;

int main() {
    try {
        const scene::TriangleMesh mesh = scene::make_procedural(scene::ProceduralKind::kSoup, 20000, 7);
        for (accel::BuilderKind kind : {accel::BuilderKind::kBinned, accel::BuilderKind::kSbvh}) {
            const accel::BuildResult r = accel::run_builder(kind, mesh, {});
            const accel::TreeStats s = accel::compute_stats(r.tree, mesh, {}, false);
            std::printf("%-7s %zu triangles: %llu nodes, SAH %.3f\n", accel::builder_name(kind), mesh.triangle_count(),
                        (unsigned long long)s.nodes, s.sah);
        }
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "build_only: %s\n", e.what());
        return 1;
    }
}
