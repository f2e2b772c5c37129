// SPDX-License-Identifier: MIT
#include "traversal/gpu/gpu_builder.h"

#include <string>

#include "accel/core/check.h"

namespace bvhlab::trav {

GpuBuild build_on_gpu(const scene::TriangleMesh& mesh, accel::BuilderKind kind, const accel::BuilderOptions& options,
                      bool keep_raw) {
    const std::string name = accel::builder_name(kind);
    if (!accel::runs_on_gpu(kind)) throw Error("builder '" + name + "' runs on the CPU, not the GPU");
    std::string why;
    if (!gpu_available(&why)) throw Error("builder '" + name + "' runs on the GPU, and there is none: " + why);
    if (const std::string p = accel::options_problem(options); !p.empty()) throw Error(p);
    const size_t n = mesh.triangle_count();
    if (n == 0) throw Error("the mesh has no triangles to build a structure over");
    if (n - 1 > accel::Bvh2Node::kMaxLeafFirst)
        throw Error("the BVH2 layout holds at most 2^25 triangle references; the mesh has " + std::to_string(n));
    return detail::gpu_build(mesh, kind, options, keep_raw);
}

std::vector<GpuBuildTimes> time_gpu_builds(const scene::TriangleMesh& mesh, accel::BuilderKind kind,
                                           const accel::BuilderOptions& options, int runs, int warmup) {
    if (runs < 1 || warmup < 0) throw Error("time_gpu_builds needs runs >= 1 and warmup >= 0");
    std::vector<GpuBuildTimes> out;
    for (int k = 0; k < warmup + runs; ++k) {
        const GpuBuildTimes t = build_on_gpu(mesh, kind, options).times;
        if (k >= warmup) out.push_back(t);
    }
    return out;
}

}  // namespace bvhlab::trav
