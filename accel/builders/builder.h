// SPDX-License-Identifier: MIT
// Builder selection by name, for the CLI and the benchmarks.
#pragma once

#include <string>

#include "accel/builders/binned_sah.h"
#include "accel/core/build_tree.h"
#include "accel/core/mesh.h"

namespace bvhlab::accel {

enum class BuilderKind { kBinned, kSweep };

/// "binned" or "sweep"; throws bvhlab::Error otherwise.
BuilderKind parse_builder_kind(const std::string& name);
const char* builder_name(BuilderKind kind);

/// Options of every builder; `num_bins` only matters for the binned one.
struct BuilderOptions {
    BuildConfig config;
    int num_bins = BinnedSahBuilder::Config{}.num_bins;
};

struct BuildResult {
    BuildTree tree;
    double build_ms = 0.0;  ///< wall time of the builder call alone
};

BuildResult run_builder(BuilderKind kind, const TriangleMesh& mesh, const BuilderOptions& options);

}  // namespace bvhlab::accel
