// SPDX-License-Identifier: MIT
#include "accel/builders/builder.h"

#include <chrono>
#include <sstream>

#include "accel/builders/reinsertion.h"
#include "accel/builders/sbvh.h"
#include "accel/builders/sweep_sah.h"
#include "accel/core/check.h"

namespace bvhlab::accel {

std::string options_problem(const BuilderOptions& o) {
    const BuildConfig& c = o.config;
    for (const std::string& p :
         {range_problem("bins", o.num_bins, 2, 256), range_problem("max_leaf", c.max_leaf_size, 1u, 64u),
          range_problem("min_leaf", c.min_leaf_size, 1u, 64u),
          range_problem("max_depth", c.max_depth, 1u, kMaxTreeDepth),
          range_problem("ct", c.traversal_cost, 0.001f, 1e6f), range_problem("ci", c.intersection_cost, 0.001f, 1e6f),
          range_problem("alpha", o.sbvh_alpha, 0.0f, 1.0f), range_problem("budget", o.sbvh_budget, 1.0f, 16.0f),
          range_problem("spatial_bins", o.sbvh_spatial_bins, 2, 256),
          range_problem("reinsertion_passes", o.reinsertion_passes, -1, 16),
          range_problem("radius", o.ploc_radius, 1, 16), range_problem("clusters", o.cluster_alpha, 0.0f, 16.0f)})
        if (!p.empty()) return p;
    if (o.cluster_alpha > 0.0f && o.cluster_alpha < 1.0f) {
        std::ostringstream s;
        s << "clusters " << o.cluster_alpha << " is neither 0 (off) nor in [1, 16]";
        return s.str();
    }
    if (o.morton_bits != 30 && o.morton_bits != 60)
        return "morton_bits " + std::to_string(o.morton_bits) + " is neither 30 nor 60";
    if (c.min_leaf_size > c.max_leaf_size)
        return "min_leaf " + std::to_string(c.min_leaf_size) + " is larger than max_leaf " +
               std::to_string(c.max_leaf_size);
    return "";
}

BuilderKind parse_builder_kind(const std::string& name) {
    if (name == "binned") return BuilderKind::kBinned;
    if (name == "sweep") return BuilderKind::kSweep;
    if (name == "sbvh") return BuilderKind::kSbvh;
    if (name == "lbvh") return BuilderKind::kLbvh;
    if (name == "ploc") return BuilderKind::kPloc;
    if (name == "hploc") return BuilderKind::kHploc;
    if (name == "gpu-binned") return BuilderKind::kGpuBinned;
    throw Error("unknown builder '" + name + "' (expected binned, sweep, sbvh, lbvh, ploc, hploc or gpu-binned)");
}

const char* builder_name(BuilderKind kind) {
    switch (kind) {
        case BuilderKind::kBinned:
            return "binned";
        case BuilderKind::kSweep:
            return "sweep";
        case BuilderKind::kSbvh:
            return "sbvh";
        case BuilderKind::kLbvh:
            return "lbvh";
        case BuilderKind::kPloc:
            return "ploc";
        case BuilderKind::kHploc:
            return "hploc";
        case BuilderKind::kGpuBinned:
            return "gpu-binned";
    }
    return "unknown";
}

int reinsertion_passes(BuilderKind kind, const BuilderOptions& options) {
    if (options.reinsertion_passes >= 0) return options.reinsertion_passes;
    return kind == BuilderKind::kSbvh ? SbvhBuilder::Config{}.reinsertion_passes : 0;
}

BuildResult run_builder(BuilderKind kind, const scene::TriangleMesh& mesh, const BuilderOptions& options) {
    if (runs_on_gpu(kind))
        throw Error(std::string("builder '") + builder_name(kind) + "' runs on the GPU (trav::build_on_gpu)");
    BuildResult r;
    ProgressCounter progress(options.progress, mesh.triangle_count(), options.progress_period_s);
    BuildConfig config = options.config;
    if (options.progress) config.progress = &progress;
    const auto t0 = std::chrono::steady_clock::now();
    if (kind == BuilderKind::kBinned) {
        BinnedSahBuilder::Config c;
        static_cast<BuildConfig&>(c) = config;
        c.num_bins = options.num_bins;
        r.tree = BinnedSahBuilder(c).build(mesh);
    } else if (kind == BuilderKind::kSweep) {
        SweepSahBuilder::Config c;
        static_cast<BuildConfig&>(c) = config;
        r.tree = SweepSahBuilder(c).build(mesh);
    } else {
        SbvhBuilder::Config c;
        static_cast<BuildConfig&>(c) = config;
        c.object_bins = options.num_bins;
        c.alpha = options.sbvh_alpha;
        c.reference_budget = options.sbvh_budget;
        c.spatial_bins = options.sbvh_spatial_bins;
        c.reinsertion_passes = reinsertion_passes(kind, options);
        r.tree = SbvhBuilder(c).build(mesh);
    }
    if (kind != BuilderKind::kSbvh) optimize_by_reinsertion(r.tree, options.config, reinsertion_passes(kind, options));
    r.build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    progress.finish();
    return r;
}

}  // namespace bvhlab::accel
