// SPDX-License-Identifier: MIT
// Probe: device time of a GPU refit (trav::GpuRefitter) of a scene whose vertices move by a
// travelling wave, frame by frame, beside a full rebuild with the GPU builders. One JSON line.
// Usage: refit_timing SCENE.obj [builder ...] (default: binned hploc)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "scene/io/obj_loader.h"
#include "traversal/factory.h"
#include "traversal/gpu/gpu_builder.h"

using namespace bvhlab;

int main(int argc, char** argv) {
    if (argc < 2) return 2;
    const scene::TriangleMesh mesh = scene::load_obj(argv[1]);
    std::vector<std::string> builders;
    for (int i = 2; i < argc; ++i) builders.push_back(argv[i]);
    if (builders.empty()) builders = {"binned", "hploc"};
    const float d = mesh.diagonal();
    for (const std::string& builder : builders) {
        trav::StructureSpec spec;
        spec.builder = builder;
        spec.epo = false;
        const trav::AccelStructure a = trav::build_structure(mesh, spec);
        trav::GpuRefitter r(a.structure, mesh);
        std::vector<double> ms, up;
        for (int frame = 0; frame < 21; ++frame) {
            std::vector<Vec3> v = mesh.vertices;
            for (Vec3& p : v) p.y += 0.01f * d * std::sin(6.0f * p.x / d + 0.3f * float(frame));
            const trav::GpuBuildTimes t = r.refit(v);
            if (frame) {
                ms.push_back(t.total_ms);
                up.push_back(t.upload_ms);
            }
        }
        std::sort(ms.begin(), ms.end());
        std::sort(up.begin(), up.end());
        nlohmann::json j{{"scene", argv[1]},
                         {"triangles", mesh.triangle_count()},
                         {"builder", builder},
                         {"refit_median_ms", ms[ms.size() / 2]},
                         {"refit_mtris_per_s", double(mesh.triangle_count()) / (ms[ms.size() / 2] * 1e3)},
                         {"upload_median_ms", up[up.size() / 2]},
                         {"nodes", a.structure.bvh2.nodes.size()}};
        std::printf("%s\n", j.dump().c_str());
    }
}
