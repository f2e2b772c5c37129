// SPDX-License-Identifier: MIT
// A tracer: one way of answering a ray set over one structure, on the CPU (the shared
// traversals under TBB) or on the GPU (a kernel from the registry). The CLI, the benchmarks
// and the tests hold one tracer and never ask which kind it is.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "traversal/device/bvh2_traverse.h"
#include "traversal/rays/ray_file.h"
#include "traversal/structure.h"

namespace bvhlab::trav {

class Tracer {
public:
    virtual ~Tracer() = default;
    /// The kernel's name for figures, e.g. "cpu-bvh2-stack" or "speculative".
    virtual std::string name() const = 0;
    /// "cpu", "gpu" or "embree".
    virtual std::string device() const = 0;
    /// GPU threads per block (0 off the GPU).
    virtual int block_size() const { return 0; }
    /// Short-stack entries of a kd-tree traversal with restart (0 for a full stack).
    virtual int short_stack() const { return 0; }
    /// Idle lanes that start new rays, for dynamic-fetch kernels (0 otherwise).
    virtual int fetch_threshold() const { return 0; }
    /// Makes `rays` the set that run() traces (a GPU tracer uploads them here).
    virtual void set_rays(const std::vector<Ray>& rays, Query query) = 0;
    /// Traces the set once and returns the milliseconds it took: kernel time from CUDA events
    /// on the GPU (uploads and the output poisoning excluded), wall clock on the CPU.
    virtual double run() = 0;
    /// The last run's hits, one per ray.
    virtual void hits(std::vector<Hit>& out) const = 0;

    /// set_rays, run, hits.
    void trace(const RaySet& set, std::vector<Hit>& out) {
        set_rays(set.rays, set.query);
        run();
        hits(out);
    }
};

/// The CPU tracer of a structure: "cpu-bvh2-stack", or for kd-trees "cpu-kd-stack" (full
/// stack, kd_stack = 64) and "cpu-kd-shortstack-N" (kd_stack = N in 1..8). `structure` must
/// outlive the tracer. Throws bvhlab::Error for a tree deeper than the stack.
std::unique_ptr<Tracer> make_cpu_tracer(const Structure& structure, int kd_stack = 64);

/// Traces a set on the CPU into `hits`, also recording per-ray work when `counters` is given.
void trace_cpu_counted(const Structure& structure, int kd_stack, const RaySet& set, std::vector<Hit>& hits,
                       std::vector<TraversalCounters>* counters);

}  // namespace bvhlab::trav
