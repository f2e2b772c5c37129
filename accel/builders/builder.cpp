// SPDX-License-Identifier: MIT
#include "accel/builders/builder.h"

#include <chrono>

#include "accel/builders/sweep_sah.h"
#include "accel/core/check.h"

namespace bvhlab::accel {

BuilderKind parse_builder_kind(const std::string& name) {
    if (name == "binned") return BuilderKind::kBinned;
    if (name == "sweep") return BuilderKind::kSweep;
    throw Error("unknown builder '" + name + "' (expected binned or sweep)");
}

const char* builder_name(BuilderKind kind) { return kind == BuilderKind::kBinned ? "binned" : "sweep"; }

BuildResult run_builder(BuilderKind kind, const TriangleMesh& mesh, const BuilderOptions& options) {
    BuildResult r;
    const auto t0 = std::chrono::steady_clock::now();
    if (kind == BuilderKind::kBinned) {
        BinnedSahBuilder::Config c;
        static_cast<BuildConfig&>(c) = options.config;
        c.num_bins = options.num_bins;
        r.tree = BinnedSahBuilder(c).build(mesh);
    } else {
        SweepSahBuilder::Config c;
        static_cast<BuildConfig&>(c) = options.config;
        r.tree = SweepSahBuilder(c).build(mesh);
    }
    r.build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return r;
}

}  // namespace bvhlab::accel
