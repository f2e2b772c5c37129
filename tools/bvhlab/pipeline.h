// SPDX-License-Identifier: MIT
// The steps the subcommands compose: build (+ validate + stats + layout) into one structure
// object, choose the tracers (--device, --kernel), benchmark a ray set (checked against
// Embree before it is timed), verify a ray set against Embree. Each returns its JSON record.
#pragma once

#include <nlohmann/json.hpp>

#include <memory>
#include <optional>

#include "accel/io/tree_file.h"
#include "tools/bvhlab/context.h"
#include "traversal/factory.h"
#include "traversal/oracle/compare.h"
#include "traversal/oracle/embree_oracle.h"
#include "traversal/tracer.h"

namespace bvhlab::cli {

/// One structure, whatever its kind (the library's AccelStructure), with its "build" JSON line.
struct Built : trav::AccelStructure {
    nlohmann::json record;  ///< the "build" JSON line: base fields, the build figures, machine
};

/// The factory's build_structure (or, for --structure FILE, structure_from_file after the
/// options given explicitly are checked against the file), with progress lines.
Built build_scene(const Scene& scene, const BuildOptions& opts, const Globals& g);

/// Which tracers a command uses: --device, --kernel, --block-size (and --kd-stack, which
/// BuildOptions holds).
struct TraceOptions {
    std::string device = "cpu";  ///< cpu, gpu, or (bench only) embree
    std::string kernel;          ///< GPU kernel name, "all", or "" for the structure's default
    int block_size = 0;          ///< GPU threads per block; 0 = the kernel's default
    int fetch_threshold = 0;     ///< dynamic-fetch kernels: idle lanes that start new rays; 0 = default
    CLI::Option* kernel_flag = nullptr;
    CLI::Option* block_flag = nullptr;
    CLI::Option* fetch_flag = nullptr;

    /// Adds --device (with `embree` when allow_embree), --kernel and --block-size.
    void add_to(CLI::App& app, bool allow_embree = false);
    /// Refuses options that do not apply (one-line bvhlab::Error), and a GPU that is missing.
    /// A --kernel that traces a CWBVH sets build.layout to cwbvh (unless --layout said otherwise,
    /// which is refused); on the CPU --kernel names the kernel whose traversal the CPU runs.
    void validate(BuildOptions& build) const;
};

/// The first option that sets up a structure (--structure, --builder, --layout, --bins, the kd
/// flags, ...) given on the command line, or null: for commands that trace with Embree alone.
const CLI::Option* given_structure_flag(const BuildOptions& build);

/// The tracers of one command over `built`: one for the CPU, one per kernel on the GPU (all
/// of the structure's layout for --kernel all), Embree's for --device embree (`oracle`
/// required then). Throws bvhlab::Error for a kernel that does not fit.
std::vector<std::unique_ptr<trav::Tracer>> make_tracers(Built& built, const TraceOptions& t, const BuildOptions& b,
                                                        const trav::EmbreeOracle* oracle);

/// A ray set with Embree's answers, computed once and shared by every tracer checked on it.
struct CheckedSet {
    const trav::RaySet& set;
    std::string ray_type;
    std::vector<trav::Hit> reference;
};

/// Embree's answers for a set (the reference of every check on it).
CheckedSet check_set(const trav::EmbreeOracle& oracle, const trav::RaySet& set, const std::string& ray_type);

/// The fields that name what traced: device, structure, layout, kernel, and on the GPU the
/// GPU and driver.
nlohmann::json tracer_fields(const Built& built, const trav::Tracer& tracer);

/// Compares `ours` with Embree's answers; the record has rays, agree, ties, mismatches.
/// Prints the first mismatches on stderr.
nlohmann::json verify_hits(const Scene& scene, const trav::EmbreeOracle& oracle, const CheckedSet& cs,
                           const std::vector<trav::Hit>& ours, const trav::CompareConfig& cc);

struct BenchSettings {
    int runs = 10;
    int warmup = 1;
};

/// Traces the set once and checks every hit against Embree; a tracer with a real mismatch
/// gets a record with "status": "failed" and is never timed. Otherwise: warm-up, then the
/// median of `runs` timed runs. `hits` receives the last run's hits.
nlohmann::json bench_ray_set(const Scene& scene, const Built& built, trav::Tracer& tracer,
                             const trav::EmbreeOracle& oracle, const CheckedSet& cs, const BenchSettings& bs,
                             const trav::CompareConfig& cc, const Globals& g, std::vector<trav::Hit>* hits = nullptr,
                             nlohmann::json* verify_record = nullptr);

/// Per-ray work of the structure's own traversal on the set (nodes, leaves, triangle tests
/// and short-stack restarts, means), counted on the CPU.
nlohmann::json work_per_ray(const Built& built, int kd_stack, const trav::RaySet& set);

/// Adds --edge-eps and --t-tol.
void add_compare_options(CLI::App& app, trav::CompareConfig& cc);

}  // namespace bvhlab::cli
