// SPDX-License-Identifier: MIT
// The front door of the library: a mesh and a structure spec (builder, layout, options) in, a
// traceable structure out, with its build figures, its device upload on demand, its default
// kernel and its tracers. The CLI, the tests, the benchmarks, the renderer's driver and the
// Python module all build structures here; nothing else chooses a builder or a kernel.
// Modelled on Embree's bvh4_factory (builders and traversers chosen by name inside the
// library) and madmann91/bvh's default_builder.h.
#pragma once

#include <nlohmann/json.hpp>

#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "accel/builders/builder.h"
#include "accel/builders/kdtree.h"
#include "accel/core/stats.h"
#include "accel/io/tree_file.h"
#include "scene/mesh.h"
#include "scene/scene.h"
#include "traversal/gpu/device_structure.h"
#include "traversal/gpu/gpu_tracer.h"
#include "traversal/gpu/registry.h"
#include "traversal/structure.h"
#include "traversal/tracer.h"

namespace bvhlab::trav {

/// What to build. The defaults are the CLI's: a binned SAH BVH in the BVH2 layout.
struct StructureSpec {
    std::string builder = "binned";   ///< binned (also "bvh"), sweep, sbvh, kdtree; lbvh, ploc, hploc, gpu-binned (GPU)
    std::string layout = "bvh2";      ///< a BVH's traversal layout: bvh2 or cwbvh (8-wide, compressed)
    accel::BuilderOptions options;    ///< the BVH builders' options (bins, leaf sizes, SBVH, reinsertion)
    accel::KdTreeBuilder::Config kd;  ///< the kd-tree builder's constants
    std::string collapse = "sah";     ///< cwbvh: sah (least wide SAH) or greedy
    std::string cw_tris = "woop";     ///< cwbvh leaf triangles: woop (48 B) or vertices (36 B)
    int kd_stack = kKdFullStack;      ///< kd-tree traversal: 64 = full stack, 1..8 = short stack with restart
    bool epo = true;                  ///< compute the EPO of a BVH (slow on very large scenes)
    /// Where the builder runs: auto (its own device), cpu, or gpu; cpu with lbvh/hploc or gpu
    /// with a CPU builder is refused.
    std::string build_device = "auto";

    bool is_kdtree() const { return builder == "kdtree"; }
    bool is_cwbvh() const { return !is_kdtree() && layout == "cwbvh"; }
    /// Whether the builder runs on the GPU (lbvh, ploc, hploc, gpu-binned).
    bool on_gpu() const { return !is_kdtree() && accel::runs_on_gpu(kind()); }
    /// The BVH builder (throws bvhlab::Error for kdtree or an unknown name).
    accel::BuilderKind kind() const;
    /// Refuses, with a one-line bvhlab::Error naming the value, any field out of its range or
    /// a combination that does not exist (a kd-tree in the cwbvh layout, min leaf > max leaf).
    void check() const;
};

/// One stage of a long call as its caller sees it: report(done, total) comes now and then while
/// a build or EPO runs (from a worker thread, never from two at once, done < total until the
/// last); the stage ends when the object is destroyed.
class StageProgress {
public:
    virtual ~StageProgress() = default;
    virtual void report(uint64_t done, uint64_t total) {
        (void)done;
        (void)total;
    }
};

/// Progress: called when a stage starts, with what it does; the stage ends when the returned
/// object is destroyed (null is fine). The CLI prints "[bvhlab] ... done (s)" lines with it, and
/// the percentage and time left of builds and EPO.
using StageHook = std::function<std::shared_ptr<StageProgress>(const std::string& what)>;

/// A built (or loaded) structure in its traversal layout, with everything known about it.
class AccelStructure {
public:
    StructureSpec spec;                              ///< what it is (for a loaded file: the file's builder and options)
    Structure structure;                             ///< the layout every tracer takes
    accel::BuildResult result;                       ///< the binary BuildTree of a BVH (empty for a kd-tree)
    accel::TreeStats stats;                          ///< a BVH's figures (for a kd-tree only .sah is set)
    nlohmann::json figures;                          ///< the build figures as JSON (builder, nodes, sah, ...)
    std::optional<accel::TreeFileMeta> loaded_meta;  ///< provenance when loaded from a structure file

    bool is_kd() const { return structure.layout == Layout::kKd; }

    /// The structure on the GPU, uploaded on the first call. Throws bvhlab::Error without one.
    std::shared_ptr<const DeviceStructure> device();
    /// The structure on the GPU if device() has uploaded it, else null.
    std::shared_ptr<const DeviceStructure> uploaded() const { return device_; }
    /// The registry's default kernel for this layout (for a kd-tree: the one whose stack
    /// matches spec.kd_stack). Throws bvhlab::Error in a build without CUDA.
    const KernelInfo& default_kernel() const;
    /// The GPU options that spec.kd_stack implies for `kernel`.
    GpuTraceOptions gpu_options(const KernelInfo& kernel) const;

    /// The CPU tracer of the structure (the object must outlive it).
    std::unique_ptr<Tracer> cpu_tracer() const;
    /// A GPU tracer with `kernel` ("" = the default kernel); uploads the structure first.
    /// Throws bvhlab::Error for a kernel that does not fit the layout, depth or options.
    std::unique_ptr<Tracer> gpu_tracer(const std::string& kernel = "", std::optional<GpuTraceOptions> opts = {});

    /// Writes the tree to a structure file (`bvhlab build --out`), checksummed and stamped with
    /// the scene's triangle count and hash; a loaded structure keeps its provenance.
    void save(const std::string& path, const std::string& scene_hash) const;

private:
    friend AccelStructure build_structure(const scene::TriangleMesh& mesh, const StructureSpec& spec,
                                          const StageHook& stage);
    std::shared_ptr<const DeviceStructure> device_;
};

struct GpuBuildTimes;
/// A GPU build's device time per stage as JSON (upload_ms ... convert_ms; the total apart): the
/// `gpu_build` figures of a build and the `gpu_tlas` figures of a TLAS rebuild.
nlohmann::json gpu_stage_times(const GpuBuildTimes& t);

struct GpuBuild;
/// A GPU build of `triangles` triangles as its `gpu_build` figures: gpu_stage_times, the
/// reinsertion passes run (and whether they were undone), the clusters binned (gpu-binned with a
/// cluster alpha only), total_ms, mtris_per_s and peak_device_bytes.
nlohmann::json gpu_build_figures(const GpuBuild& g, size_t triangles);

/// Builds `spec` over `mesh`: builder, validation (throws bvhlab::Error on an invalid tree),
/// figures (SAH, EPO, sizes), and the traversal layout. A GPU builder's BVH2 stays on the device
/// as built (device() returns it without an upload); its figures add "gpu_build" (the device
/// time of each stage, Mtris/s and peak device memory).
AccelStructure build_structure(const scene::TriangleMesh& mesh, const StructureSpec& spec, const StageHook& stage = {});

/// Builds the two-level BVH of an instanced scene: a BLAS per placed mesh by spec's BVH builder
/// and options, each validated, in spec's layout (bvh2, or cwbvh with its collapse and triangle
/// format), under a binned TLAS (layout "two-level" or "two-level-cwbvh", name
/// "two-level/<builder>" or "two-level-cwbvh/<builder>"; hits name triangles by scene-wide ids,
/// accel::TwoLevelBvh). Throws bvhlab::Error for the kd-tree (single-level: flatten the scene
/// first).
AccelStructure build_structure(const scene::InstancedScene& scene, const StructureSpec& spec,
                               const StageHook& stage = {});

/// The structure of a structure file already read (`path` names it in errors and figures):
/// its tree, validated, in the layout of `spec` (layout, collapse, cw_tris, kd_stack, epo);
/// builder and options come from the file. Throws bvhlab::Error for a file whose triangle
/// count or scene hash differ from the mesh's, or a layout that does not apply.
AccelStructure structure_from_file(const scene::TriangleMesh& mesh, const std::string& scene_hash, accel::TreeFile file,
                                   const std::string& path, const StructureSpec& spec = {},
                                   const StageHook& stage = {});

/// Reads a structure file and returns structure_from_file of it.
AccelStructure load_structure(const scene::TriangleMesh& mesh, const std::string& scene_hash, const std::string& path,
                              const StructureSpec& spec = {}, const StageHook& stage = {});

/// The layout whose CPU traversal is the one GPU kernel `name` runs (the CPU reference behind
/// `--device cpu --kernel NAME`: plain for BVH2, cwbvh for CWBVH), or none.
std::optional<Layout> cpu_reference_layout(const std::string& name);

}  // namespace bvhlab::trav
