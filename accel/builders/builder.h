// SPDX-License-Identifier: MIT
// Builder selection by name, for the CLI and the benchmarks.
#pragma once

#include <string>

#include "accel/builders/binned_sah.h"
#include "accel/core/build_tree.h"
#include "scene/mesh.h"

namespace bvhlab::accel {

enum class BuilderKind { kBinned, kSweep, kSbvh };

/// "binned", "sweep" or "sbvh"; throws bvhlab::Error otherwise.
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

BuildResult run_builder(BuilderKind kind, const scene::TriangleMesh& mesh, const BuilderOptions& options);

}  // namespace bvhlab::accel
