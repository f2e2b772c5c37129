// SPDX-License-Identifier: MIT
// Builder selection by name, for the CLI and the benchmarks.
#pragma once

#include <string>

#include "accel/builders/binned_sah.h"
#include "accel/core/build_tree.h"
#include "accel/core/progress.h"
#include "scene/mesh.h"

namespace bvhlab::accel {

/// The CPU builders, and the GPU builders (traversal/gpu/gpu_builder.h; their codes skip 3, the
/// kd-tree's in structure files).
enum class BuilderKind { kBinned = 0, kSweep = 1, kSbvh = 2, kLbvh = 4, kPloc = 5, kHploc = 6, kGpuBinned = 7 };

/// Whether `kind` runs on the GPU (lbvh, ploc, hploc, gpu-binned).
inline bool runs_on_gpu(BuilderKind kind) {
    return kind == BuilderKind::kLbvh || kind == BuilderKind::kPloc || kind == BuilderKind::kHploc ||
           kind == BuilderKind::kGpuBinned;
}

/// Whether `kind` orders the triangles by Morton codes and so takes their bits (lbvh, ploc, hploc).
inline bool uses_morton(BuilderKind kind) {
    return kind == BuilderKind::kLbvh || kind == BuilderKind::kPloc || kind == BuilderKind::kHploc;
}

/// Whether `kind` clusters by PLOC's rule and so takes a search radius (ploc, hploc).
inline bool uses_radius(BuilderKind kind) { return kind == BuilderKind::kPloc || kind == BuilderKind::kHploc; }

/// Whether `kind` takes a cluster alpha (gpu-binned).
inline bool uses_clusters(BuilderKind kind) { return kind == BuilderKind::kGpuBinned; }

/// Whether `kind` may reference a triangle more than once (SBVH's spatial splits), so that its
/// trees are validated with ValidateOptions::allow_duplicates; every other builder's reference
/// each triangle exactly once.
inline bool splits_references(BuilderKind kind) { return kind == BuilderKind::kSbvh; }

/// "binned", "sweep", "sbvh", "lbvh", "ploc", "hploc" or "gpu-binned"; throws bvhlab::Error otherwise.
BuilderKind parse_builder_kind(const std::string& name);
const char* builder_name(BuilderKind kind);

/// Options of every builder; `num_bins` applies to binned and SBVH object bins, the sbvh_*
/// fields to SBVH only.
struct BuilderOptions {
    BuildConfig config;
    int num_bins = BinnedSahBuilder::Config{}.num_bins;
    float sbvh_alpha = 1e-5f;
    float sbvh_budget = 2.0f;
    int sbvh_spatial_bins = 32;
    /// Passes of subtree reinsertion after the build; -1 = the builder's default (3 for SBVH,
    /// 0 for the others). See reinsertion_passes().
    int reinsertion_passes = -1;
    /// The GPU builders: bits of the Morton codes (30 or 60).
    int morton_bits = 30;
    /// H-PLOC: how many clusters to each side a cluster looks at for its nearest neighbour.
    int ploc_radius = 8;
    /// gpu-binned: 0 bins every triangle (the CPU binned tree, node for node); from 1 to 16, bins
    /// clusters of nearly coincident triangles instead: neighbours in the Morton order merge
    /// while their union's half area is at most this many times the larger one's, at most 16
    /// triangles a cluster (accel::triangle_clusters). Fewer primitives to bin where triangles
    /// overlap (hair, fur, foliage), the same splits elsewhere. A TLAS over instances bins every
    /// instance.
    float cluster_alpha = 0.0f;
    /// Not part of the configuration: when set, run_builder reports the CPU builders' progress
    /// with it (references in finished leaves of the triangle count; the reinsertion passes that
    /// follow at 99%).
    ProgressFn progress;
    /// The least time between two of those reports, in seconds (the last one, done, always comes).
    double progress_period_s = 0.25;
};

/// "" when every option is in its range, else one line naming the first that is not, by its
/// structure-spec name ("bins 300 is not in [2, 256]"). Structure specs and structure-file
/// headers are checked with it.
std::string options_problem(const BuilderOptions& options);

/// The reinsertion passes `options` ask of builder `kind`, with -1 resolved.
int reinsertion_passes(BuilderKind kind, const BuilderOptions& options);

struct BuildResult {
    BuildTree tree;
    double build_ms = 0.0;  ///< wall time of the builder call alone
};

/// Runs a CPU builder; throws bvhlab::Error for a GPU builder (trav::build_on_gpu runs those).
BuildResult run_builder(BuilderKind kind, const scene::TriangleMesh& mesh, const BuilderOptions& options);

}  // namespace bvhlab::accel
