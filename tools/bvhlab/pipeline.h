// SPDX-License-Identifier: MIT
// The steps the subcommands compose: build (+ validate + stats + layout), benchmark a ray
// set, verify a ray set against Embree. Each returns its JSON record.
#pragma once

#include <nlohmann/json.hpp>

#include <optional>

#include "accel/io/tree_file.h"

#include "accel/layouts/bvh2_node.h"
#include "tools/bvhlab/context.h"
#include "traversal/oracle/compare.h"
#include "traversal/cpu/kd_trace.h"
#include "traversal/launch.h"
#include "traversal/oracle/embree_oracle.h"

namespace bvhlab::cli {

struct Built {
    accel::BuildResult result;
    accel::TreeStats stats;
    accel::Bvh2 bvh;
    std::string structure;  ///< e.g. "bvh2/binned"
    nlohmann::json record;  ///< the "build" JSON line
    std::shared_ptr<trav::GpuBvh2> gpu;  ///< uploaded on first GPU use
    std::shared_ptr<trav::KdTracer> kd;  ///< set instead of bvh for --structure kdtree
    std::string kernel;                  ///< CPU kernel name, e.g. cpu-bvh2-stack
    std::optional<accel::TreeFileMeta> loaded_meta;  ///< provenance when loaded from a structure file
};

/// Traces a set on the CPU with whatever structure `built` holds; fills counters if non-null.
void trace_cpu_any(const Built& built, const trav::RaySet& set, std::vector<trav::Hit>& hits,
                   std::vector<trav::TraversalCounters>* counters = nullptr);

/// Builds, validates (throws on an invalid tree), computes statistics and converts to Bvh2.
Built build_scene(const Scene& scene, const BuildOptions& opts, const Globals& g);

struct BenchSettings {
    int runs = 5;
    int warmup = 1;
    std::string device = "cpu";  ///< cpu or gpu
};

/// Traces a set once on `device` (cpu or gpu) and returns the hits.
std::vector<trav::Hit> trace_on(Built& built, const trav::RaySet& set, const std::string& device);

/// Name of the kernel that traces `built` on a device, for the JSON records.
std::string kernel_name(const Built& built, const std::string& device);

/// Adds --device (cpu or gpu).
void add_device_option(CLI::App& app, std::string& device);

/// Times trace_cpu over the set; the record has mrays_per_s (from the median run) and the
/// provenance keys. `hits` receives the last run's hits.
nlohmann::json bench_ray_set(const Scene& scene, Built& built, const trav::RaySet& set,
                             const std::string& ray_type, const BenchSettings& bs, const Globals& g,
                             std::vector<trav::Hit>* hits = nullptr);

/// Compares `ours` with Embree's answers; the record has rays, agree, ties, mismatches.
/// Prints the first mismatches on stderr.
nlohmann::json verify_ray_set(const Scene& scene, const trav::EmbreeOracle& oracle, const trav::RaySet& set,
                              const std::vector<trav::Hit>& ours, const std::string& ray_type,
                              const std::string& structure, const trav::CompareConfig& cc, const Globals& g,
                              const std::string& device = "cpu", const std::string& kernel = "cpu-bvh2-stack");

/// Adds --edge-eps and --t-tol.
void add_compare_options(CLI::App& app, trav::CompareConfig& cc);

}  // namespace bvhlab::cli
