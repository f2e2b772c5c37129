// SPDX-License-Identifier: MIT
#include "accel/builders/builder.h"

#include <chrono>

#include "accel/builders/reinsertion.h"
#include "accel/builders/sbvh.h"
#include "accel/builders/sweep_sah.h"
#include "accel/core/check.h"

namespace bvhlab::accel {

BuilderKind parse_builder_kind(const std::string& name) {
    if (name == "binned") return BuilderKind::kBinned;
    if (name == "sweep") return BuilderKind::kSweep;
    if (name == "sbvh") return BuilderKind::kSbvh;
    throw Error("unknown builder '" + name + "' (expected binned, sweep or sbvh)");
}

const char* builder_name(BuilderKind kind) {
    return kind == BuilderKind::kBinned ? "binned" : (kind == BuilderKind::kSweep ? "sweep" : "sbvh");
}

int reinsertion_passes(BuilderKind kind, const BuilderOptions& options) {
    if (options.reinsertion_passes >= 0) return options.reinsertion_passes;
    return kind == BuilderKind::kSbvh ? SbvhBuilder::Config{}.reinsertion_passes : 0;
}

BuildResult run_builder(BuilderKind kind, const scene::TriangleMesh& mesh, const BuilderOptions& options) {
    BuildResult r;
    const auto t0 = std::chrono::steady_clock::now();
    if (kind == BuilderKind::kBinned) {
        BinnedSahBuilder::Config c;
        static_cast<BuildConfig&>(c) = options.config;
        c.num_bins = options.num_bins;
        r.tree = BinnedSahBuilder(c).build(mesh);
    } else if (kind == BuilderKind::kSweep) {
        SweepSahBuilder::Config c;
        static_cast<BuildConfig&>(c) = options.config;
        r.tree = SweepSahBuilder(c).build(mesh);
    } else {
        SbvhBuilder::Config c;
        static_cast<BuildConfig&>(c) = options.config;
        c.object_bins = options.num_bins;
        c.alpha = options.sbvh_alpha;
        c.reference_budget = options.sbvh_budget;
        c.spatial_bins = options.sbvh_spatial_bins;
        c.reinsertion_passes = reinsertion_passes(kind, options);
        r.tree = SbvhBuilder(c).build(mesh);
    }
    if (kind != BuilderKind::kSbvh) optimize_by_reinsertion(r.tree, options.config, reinsertion_passes(kind, options));
    r.build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return r;
}

}  // namespace bvhlab::accel
