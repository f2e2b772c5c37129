// SPDX-License-Identifier: MIT
#include "traversal/factory.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "accel/core/check.h"
#include "accel/core/progress.h"
#include "accel/core/validate.h"
#include "accel/layouts/bvh2_convert.h"
#include "accel/layouts/cwbvh_convert.h"
#include "accel/layouts/kd_convert.h"
#include "accel/passes/collapse_wide.h"
#include "traversal/device/kd_traverse.h"
#include "traversal/gpu/gpu_builder.h"

namespace bvhlab::trav {

namespace {

std::shared_ptr<StageProgress> begin(const StageHook& stage, const std::string& what) {
    return stage ? stage(what) : nullptr;
}

/// The stage's report() as a progress function (none without a stage).
accel::ProgressFn progress_of(const std::shared_ptr<StageProgress>& st) {
    if (!st) return {};
    return [st](uint64_t done, uint64_t total) { st->report(done, total); };
}

double ms_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

/// The kd-tree path: kd SAH and sizes (no EPO: it is a BVH figure). `tree` is built here
/// unless a loaded one is given.
AccelStructure make_kdtree(const scene::TriangleMesh& mesh, const StructureSpec& spec, const StageHook& stage,
                           accel::KdTree* loaded, const std::string& path) {
    AccelStructure b;
    b.spec = spec;
    accel::KdTreeBuilder builder(spec.kd);
    accel::KdTree tree;
    if (loaded) {
        tree = std::move(*loaded);
        tree.bounds = mesh.bounds();  // not stored: the scene hash guarantees the same box
    } else {
        auto st = begin(stage, "building SAH kd-tree over " + std::to_string(mesh.triangle_count()) + " triangles");
        accel::ProgressCounter progress(progress_of(st), mesh.triangle_count());
        accel::KdTreeBuilder::Config c = spec.kd;
        c.progress = &progress;
        const auto t0 = std::chrono::steady_clock::now();
        tree = accel::KdTreeBuilder(c).build(mesh);
        b.result.build_ms = ms_since(t0);
        progress.finish();
    }
    const std::string err = accel::validate_kd(tree, mesh.triangle_count());
    if (!err.empty())
        throw Error((loaded ? "structure file '" + path + "' holds" : std::string("the kd-tree builder produced")) +
                    " an invalid kd-tree: " + err);
    const accel::KdTreeStats ks =
        accel::compute_kd_stats(tree, builder.config().traversal_cost, builder.config().intersection_cost);
    nlohmann::json& f = b.figures;
    f["builder"] = "kdtree";
    f["structure"] = "kdtree";
    f["triangles"] = mesh.triangle_count();
    f["nodes"] = ks.nodes;
    f["leaves"] = ks.leaves;
    f["depth"] = ks.depth;
    f["max_depth"] = builder.max_depth_for(mesh.triangle_count());
    f["references"] = ks.references;
    f["mean_leaf_size"] = ks.leaves ? double(ks.references) / double(ks.leaves) : 0.0;
    f["max_leaf_size"] = ks.max_leaf_size;
    f["duplication"] = mesh.triangle_count() ? double(ks.references) / double(mesh.triangle_count()) : 0.0;
    f["bytes"] = tree.bytes();
    f["sah"] = ks.sah;
    f["sah_constants"] = {{"traversal", builder.config().traversal_cost},
                          {"intersection", builder.config().intersection_cost},
                          {"empty_bonus", builder.config().empty_bonus}};
    f["epo"] = nullptr;
    f["build_ms"] = b.result.build_ms;
    b.stats.sah = ks.sah;
    b.structure.name = "kdtree";
    b.structure.layout = Layout::kKd;
    b.structure.kd = accel::convert_to_kd_layout(std::move(tree), mesh);
    f["layout"] = layout_name(b.structure.layout);
    f["layout_bytes"] = b.structure.bytes();
    if (loaded) f["structure_file"] = path;
    return b;
}

/// The bytes of the BVH2 layout of `tree` (nodes, Woop triangles, triangle ids), without
/// building it: what a CWBVH's bytes are compared with.
size_t bvh2_layout_bytes(const accel::BuildTree& tree) {
    size_t interior = 0;
    for (const accel::BuildNode& n : tree.nodes) interior += !n.is_leaf();
    return std::max<size_t>(interior, 1) * sizeof(accel::Bvh2Node) +
           tree.prim_indices.size() * (sizeof(accel::WoopTriangle) + sizeof(uint32_t));
}

/// The CWBVH path: collapse the binary tree to 8-wide, check it, quantise.
void convert_cwbvh(const scene::TriangleMesh& mesh, const StructureSpec& spec, const StageHook& stage,
                   AccelStructure& b) {
    const auto t0 = std::chrono::steady_clock::now();
    accel::WideTree w;
    {
        auto st = begin(stage, "collapsing to an 8-wide BVH (" + spec.collapse + ") and quantising its boxes");
        w = accel::collapse_to_wide(
            b.result.tree, mesh,
            spec.collapse == "greedy" ? accel::CollapseMethod::kGreedy : accel::CollapseMethod::kSahOptimal);
        const std::string err = accel::validate_wide(w, mesh.triangle_count(), b.result.tree.prim_indices);
        BVHLAB_CHECK(err.empty(), "the collapse produced an invalid wide tree: " + err);
        b.structure.layout = Layout::kCwbvh;
        b.structure.cwbvh = accel::convert_to_cwbvh(
            w, mesh, spec.cw_tris == "vertices" ? accel::CwTris::kVertices : accel::CwTris::kWoop);
    }
    const double ms = ms_since(t0);
    const accel::WideStats ws = accel::compute_wide_stats(w);
    const size_t bvh2_bytes = bvh2_layout_bytes(b.result.tree);
    b.figures["wide"] = {{"collapse", spec.collapse},
                         {"triangles", spec.cw_tris},
                         {"collapse_ms", ms},
                         {"nodes", ws.nodes},
                         {"leaves", ws.leaves},
                         {"references", ws.references},
                         {"mean_children", ws.mean_children},
                         {"sah", ws.sah},
                         {"sah_costs", {{"node", accel::WideCost{}.node}, {"prim", accel::WideCost{}.prim}}},
                         {"depth", ws.depth},
                         {"node_bytes", b.structure.cwbvh.nodes.size() * sizeof(accel::CwbvhNode)}};
    b.figures["bvh2_layout_bytes"] = bvh2_bytes;
    b.figures["bytes_vs_bvh2"] = double(b.structure.cwbvh.bytes()) / double(bvh2_bytes);
}

/// The BVH path after the binary tree exists (built, or loaded from `path`): validation,
/// figures, layout (`built`: the BVH2 layout a GPU builder made already).
AccelStructure finish_bvh(const scene::TriangleMesh& mesh, const StructureSpec& spec, const StageHook& stage,
                          AccelStructure b, const std::string& path, accel::Bvh2* built = nullptr) {
    const std::string builder = accel::builder_name(spec.kind());
    accel::ValidateOptions vo;
    vo.allow_duplicates = accel::splits_references(spec.kind());
    const std::string err = accel::validate(b.result.tree, mesh, spec.options.config, vo);
    if (!err.empty())
        throw Error((path.empty() ? "builder '" + builder + "' produced" : "structure file '" + path + "' holds") +
                    " an invalid tree: " + err);
    {
        auto st = begin(stage, spec.epo ? "computing SAH and EPO" : "computing SAH");
        b.stats = accel::compute_stats(b.result.tree, mesh, spec.options.config, spec.epo, 0, progress_of(st));
    }
    const accel::TreeStats& s = b.stats;
    nlohmann::json& f = b.figures;
    f["builder"] = builder;
    f["triangles"] = mesh.triangle_count();
    f["dropped_non_finite"] = mesh.dropped.non_finite;
    f["dropped_zero_area"] = mesh.dropped.zero_area;
    f["nodes"] = s.nodes;
    f["leaves"] = s.leaves;
    f["depth"] = s.depth;
    f["mean_leaf_size"] = s.mean_leaf_size;
    f["max_leaf_size"] = s.max_leaf_size;
    f["references"] = s.references;
    f["duplication"] = mesh.triangle_count() ? double(s.references) / double(mesh.triangle_count()) : 0.0;
    f["bytes"] = s.bytes;
    f["sah"] = s.sah;
    f["epo"] = s.epo >= 0 ? nlohmann::json(s.epo) : nlohmann::json(nullptr);
    if (!s.epo_skipped.empty()) f["epo_skipped"] = s.epo_skipped;
    f["build_ms"] = b.result.build_ms;  // 0 for a loaded file: nothing was built
    if (spec.is_cwbvh()) {
        convert_cwbvh(mesh, spec, stage, b);
        // Woop triangles are the default and keep the plain name; vertex triples are named.
        b.structure.name = std::string(spec.cw_tris == "vertices" ? "cwbvh-vertices/" : "cwbvh/") + builder;
    } else {
        b.structure.name = "bvh2/" + builder;
        b.structure.layout = Layout::kBvh2;
        b.structure.bvh2 = built ? std::move(*built) : accel::convert_to_bvh2(b.result.tree, mesh);
    }
    f["structure"] = b.structure.name;
    f["layout"] = layout_name(b.structure.layout);
    f["layout_bytes"] = b.structure.bytes();
    f["layout_depth"] = b.structure.depth();
    f["build_device"] = spec.on_gpu() ? "gpu" : "cpu";
    if (spec.on_gpu()) {
        if (accel::uses_morton(spec.kind())) f["morton_bits"] = spec.options.morton_bits;
        if (accel::uses_radius(spec.kind())) f["radius"] = spec.options.ploc_radius;
        if (spec.kind() == accel::BuilderKind::kGpuBinned) {
            f["bins"] = 32;
            f["cluster_alpha"] = spec.options.cluster_alpha;
        }
    } else if (builder != "sweep") {
        f["bins"] = spec.options.num_bins;
    }
    if (builder == "sbvh") {
        f["alpha"] = spec.options.sbvh_alpha;
        f["budget"] = spec.options.sbvh_budget;
    }
    f["max_leaf"] = spec.options.config.max_leaf_size;
    f["reinsertion_passes"] = accel::reinsertion_passes(spec.kind(), spec.options);
    f["config"] = accel::describe_config(spec.kind(), spec.options);
    if (!path.empty()) f["structure_file"] = path;
    return b;
}

/// A GPU builder: the BVH2 layout is made on the device and kept there; the host gets a copy
/// and its BuildTree for the figures, a CWBVH collapse and structure files.
std::pair<AccelStructure, std::shared_ptr<const DeviceStructure>> build_on_device(const scene::TriangleMesh& mesh,
                                                                                  const StructureSpec& spec,
                                                                                  const StageHook& stage,
                                                                                  AccelStructure b) {
    GpuBuild g;
    {
        auto st = begin(stage, "building " + spec.builder + " BVH on the GPU over " +
                                   std::to_string(mesh.triangle_count()) + " triangles");
        g = build_on_gpu(mesh, spec.kind(), spec.options);
    }
    b.result.tree = accel::build_tree_from_bvh2(g.host);
    b.result.build_ms = g.times.total_ms;
    accel::Bvh2 built = std::move(g.host);
    b = finish_bvh(mesh, spec, stage, std::move(b), "", &built);
    b.figures["gpu_build"] = gpu_build_figures(g, mesh.triangle_count());
    std::shared_ptr<const DeviceStructure> device;
    if (b.structure.layout == Layout::kBvh2)
        device =
            std::make_shared<DeviceStructure>(b.structure, std::move(g.nodes), std::move(g.tris), std::move(g.tri_ids));
    return {std::move(b), std::move(device)};
}

}  // namespace

nlohmann::json gpu_build_figures(const GpuBuild& g, size_t triangles) {
    const GpuBuildTimes& t = g.times;
    nlohmann::json f = gpu_stage_times(t);
    f["reinsertion_passes"] = g.reinsertion_passes;
    f["reinsertion_undone"] = g.reinsertion_undone;
    if (g.clusters) f["clusters"] = g.clusters;
    f["total_ms"] = t.total_ms;
    f["mtris_per_s"] = t.total_ms > 0.0 ? double(triangles) / (t.total_ms * 1e3) : 0.0;
    f["peak_device_bytes"] = g.peak_bytes;
    return f;
}

nlohmann::json gpu_stage_times(const GpuBuildTimes& t) {
    return {{"upload_ms", t.upload_ms},  {"bounds_ms", t.bounds_ms},       {"morton_ms", t.morton_ms},
            {"sort_ms", t.sort_ms},      {"hierarchy_ms", t.hierarchy_ms}, {"optimize_ms", t.optimize_ms},
            {"convert_ms", t.convert_ms}};
}

accel::BuilderKind StructureSpec::kind() const {
    if (builder == "bvh") return accel::BuilderKind::kBinned;
    if (is_kdtree()) throw Error("builder 'kdtree' builds a kd-tree, not a BVH");
    return accel::parse_builder_kind(builder);
}

void StructureSpec::check() const {
    if (!is_kdtree()) kind();  // names an unknown builder
    if (layout != "bvh2" && layout != "cwbvh")
        throw Error("layout '" + layout + "' is not one of bvh2, cwbvh (a kd-tree has its own layout)");
    if (is_kdtree() && layout == "cwbvh")
        throw Error("layout cwbvh is built from a BVH, not a kd-tree (builder 'kdtree')");
    if (collapse != "sah" && collapse != "greedy") throw Error("collapse '" + collapse + "' is not one of sah, greedy");
    if (cw_tris != "woop" && cw_tris != "vertices")
        throw Error("cw_tris '" + cw_tris + "' is not one of woop, vertices");
    if (kd_stack != kKdFullStack && (kd_stack < 1 || kd_stack > 8))
        throw Error("kd_stack " + std::to_string(kd_stack) + " is neither 64 (full stack) nor in [1, 8] (short stack)");
    if (const std::string p = accel::options_problem(options); !p.empty()) throw Error(p);
    if (!is_kdtree() && (layout == "bvh2" || on_gpu()))  // a GPU builder writes the BVH2 layout first
        if (const std::string p = accel::bvh2_leaf_problem(options.config); !p.empty()) throw Error(p);
    if (const std::string p = accel::kd_config_problem(kd); !p.empty()) throw Error(p);
    if (build_device != "auto" && build_device != "cpu" && build_device != "gpu")
        throw Error("build_device '" + build_device + "' is not one of auto, cpu, gpu");
    if (build_device == "gpu" && !on_gpu())
        throw Error("build_device gpu applies to the GPU builders (lbvh, ploc, hploc, gpu-binned), not " + builder);
    if (build_device == "cpu" && on_gpu()) throw Error("builder '" + builder + "' runs on the GPU only");
    if (options.cluster_alpha > 0.0f && (is_kdtree() || !accel::uses_clusters(kind())))
        throw Error("clusters applies to builder gpu-binned, not " + builder);
}

AccelStructure build_structure(const scene::TriangleMesh& mesh, const StructureSpec& spec_in, const StageHook& stage) {
    spec_in.check();
    if (mesh.triangle_count() == 0) throw Error("the mesh has no triangles to build a structure over");
    if (const std::string p = scene::domain_problem(mesh); !p.empty()) throw Error(p);
    StructureSpec spec = spec_in;
    if (spec.is_kdtree()) return make_kdtree(mesh, spec, stage, nullptr, "");
    spec.builder = accel::builder_name(spec.kind());  // "bvh" -> "binned"
    AccelStructure b;
    b.spec = spec;
    if (spec.on_gpu()) {
        auto [built, device] = build_on_device(mesh, spec, stage, std::move(b));
        built.device_ = std::move(device);
        return std::move(built);
    }
    {
        auto st = begin(stage, "building " + spec.builder + " SAH BVH over " + std::to_string(mesh.triangle_count()) +
                                   " triangles");
        accel::BuilderOptions o = spec.options;
        o.progress = progress_of(st);
        b.result = accel::run_builder(spec.kind(), mesh, o);
    }
    return finish_bvh(mesh, spec, stage, std::move(b), "");
}

AccelStructure build_structure(const scene::InstancedScene& placed, const StructureSpec& spec_in,
                               const StageHook& stage) {
    spec_in.check();
    if (spec_in.is_kdtree())
        throw Error(
            "the kd-tree is single-level and the scene places a mesh more than once: --flatten makes it one "
            "mesh");
    if (placed.instances.empty()) throw Error("the scene places no mesh: nothing to build a structure over");
    for (const scene::TriangleMesh& m : placed.meshes)
        if (const std::string p = scene::domain_problem(m); !p.empty() && m.triangle_count() > 0) throw Error(p);
    StructureSpec spec = spec_in;
    spec.builder = accel::builder_name(spec.kind());
    AccelStructure b;
    b.spec = spec;
    accel::ValidateOptions vo;
    vo.allow_duplicates = accel::splits_references(spec.kind());
    const auto t0 = std::chrono::steady_clock::now();
    {
        auto st = begin(stage, "building " + std::to_string(scene::placed_mesh_count(placed)) + " " + spec.builder +
                                   " SAH BLAS" + (spec.is_cwbvh() ? " (collapsed to 8-wide)" : "") +
                                   " and the TLAS over " + std::to_string(placed.instances.size()) + " instances");
        accel::BlasLayout blas_layout;
        blas_layout.wide = spec.is_cwbvh();
        blas_layout.collapse =
            spec.collapse == "greedy" ? accel::CollapseMethod::kGreedy : accel::CollapseMethod::kSahOptimal;
        blas_layout.tris = spec.cw_tris == "vertices" ? accel::CwTris::kVertices : accel::CwTris::kWoop;
        b.structure.two_level = accel::build_two_level(
            placed,
            [&](const scene::TriangleMesh& m) {
                accel::BuildTree tree =
                    spec.on_gpu() ? accel::build_tree_from_bvh2(build_on_gpu(m, spec.kind(), spec.options).host)
                                  : accel::run_builder(spec.kind(), m, spec.options).tree;
                const std::string err = accel::validate(tree, m, spec.options.config, vo);
                if (!err.empty()) throw Error("builder '" + spec.builder + "' produced an invalid BLAS: " + err);
                return tree;
            },
            blas_layout);
    }
    b.result.build_ms = ms_since(t0);
    const accel::TwoLevelBvh& t = b.structure.two_level;
    b.structure.layout = t.wide() ? Layout::kTwoLevelCwbvh : Layout::kTwoLevel;
    b.structure.name = std::string(!t.wide()                    ? "two-level/"
                                   : spec.cw_tris == "vertices" ? "two-level-cwbvh-vertices/"
                                                                : "two-level-cwbvh/") +
                       spec.builder;
    size_t blas_nodes = 0, blas_refs = 0, blas_bytes = 0;
    for (const accel::Bvh2& x : t.blas) {
        blas_nodes += x.nodes.size();
        blas_refs += x.tri_ids.size();
        blas_bytes += x.bytes();
    }
    for (const accel::Cwbvh& x : t.cw_blas) {
        blas_nodes += x.nodes.size();
        blas_refs += x.tri_ids.size();
        blas_bytes += x.bytes();
    }
    nlohmann::json& f = b.figures;
    f["builder"] = spec.builder;
    f["structure"] = b.structure.name;
    f["layout"] = layout_name(b.structure.layout);
    f["triangles"] = t.world_triangles;
    f["stored_triangles"] = placed.stored_triangle_count();
    f["instances"] = placed.instances.size();
    f["meshes"] = scene::placed_mesh_count(placed);
    f["tlas_nodes"] = t.tlas.nodes.size();
    f["tlas_depth"] = t.tlas_depth();
    f["blas_nodes"] = blas_nodes;
    f["blas_depth"] = t.blas_depth();
    f["references"] = blas_refs;
    f["sah"] = nullptr;  // no single-level SAH: the TLAS's cost depends on the BLAS behind each leaf
    f["epo"] = nullptr;
    f["layout_bytes"] = b.structure.bytes();
    f["blas_bytes"] = blas_bytes;
    f["bytes_per_world_triangle"] = t.world_triangles ? double(b.structure.bytes()) / double(t.world_triangles) : 0.0;
    f["build_ms"] = b.result.build_ms;
    f["build_device"] = spec.on_gpu() ? "gpu" : "cpu";
    if (spec.on_gpu() && accel::uses_morton(spec.kind()))
        f["morton_bits"] = spec.options.morton_bits;
    else if (spec.builder != "sweep")
        f["bins"] = spec.options.num_bins;
    f["max_leaf"] = spec.options.config.max_leaf_size;
    f["config"] = accel::describe_config(spec.kind(), spec.options);
    return b;
}

AccelStructure structure_from_file(const scene::TriangleMesh& mesh, const std::string& scene_hash, accel::TreeFile file,
                                   const std::string& path, const StructureSpec& spec_in, const StageHook& stage) {
    const std::string stale = accel::stale_reason(file.meta, mesh.triangle_count(), scene_hash);
    if (!stale.empty()) throw Error("stale structure file '" + path + "': " + stale);
    StructureSpec spec = spec_in;
    if (file.meta.kdtree) {
        if (spec.layout == "cwbvh")
            throw Error("structure file '" + path + "' holds a kd-tree; the cwbvh layout is built from a BVH");
        spec.builder = "kdtree";
        spec.kd = file.meta.kd;
        spec.check();
        AccelStructure b = make_kdtree(mesh, spec, stage, &file.kd, path);
        b.loaded_meta = file.meta;
        return b;
    }
    spec.builder = accel::builder_name(file.meta.builder);
    spec.options = file.meta.options;
    spec.check();
    AccelStructure b;
    b.spec = spec;
    b.loaded_meta = file.meta;
    b.result.tree = std::move(file.tree);
    return finish_bvh(mesh, spec, stage, std::move(b), path);
}

AccelStructure load_structure(const scene::TriangleMesh& mesh, const std::string& scene_hash, const std::string& path,
                              const StructureSpec& spec, const StageHook& stage) {
    accel::TreeFile f;
    {
        auto st = begin(stage, "loading structure " + path);
        f = accel::read_tree_file(path);
    }
    return structure_from_file(mesh, scene_hash, std::move(f), path, spec, stage);
}

std::shared_ptr<const DeviceStructure> AccelStructure::device() {
    if (!device_) device_ = std::make_shared<DeviceStructure>(structure);
    return device_;
}

const KernelInfo& AccelStructure::default_kernel() const {
    return trav::default_kernel(structure.layout, is_kd() && spec.kd_stack != kKdFullStack);
}

GpuTraceOptions AccelStructure::gpu_options(const KernelInfo& kernel) const {
    GpuTraceOptions o;
    if (kernel.short_stack && spec.kd_stack != kKdFullStack) o.kd_stack = spec.kd_stack;
    return o;
}

std::unique_ptr<Tracer> AccelStructure::cpu_tracer() const { return make_cpu_tracer(structure, spec.kd_stack); }

std::unique_ptr<Tracer> AccelStructure::gpu_tracer(const std::string& kernel, std::optional<GpuTraceOptions> opts) {
    const KernelInfo& k = kernel.empty() ? default_kernel() : find_kernel(kernel);
    const GpuTraceOptions o = opts ? *opts : gpu_options(k);
    check_kernel_fits(k, structure.layout, structure.depth(), o);  // before anything is uploaded
    return make_gpu_tracer(device(), k, o);
}

void AccelStructure::save(const std::string& path, const std::string& scene_hash) const {
    if (is_two_level(structure.layout))
        throw Error("structure files hold single-level structures; a two-level BVH is rebuilt from its scene");
    accel::TreeFileMeta meta;
    if (loaded_meta) {  // re-saving a loaded file keeps its provenance
        meta = *loaded_meta;
    } else if (is_kd()) {
        meta.kdtree = true;
        meta.kd = spec.kd;
    } else {
        meta.builder = spec.kind();
        meta.options = spec.options;
    }
    if (!loaded_meta) {
        meta.triangles = figures.value("triangles", uint64_t(0));
        meta.scene_hash = scene_hash;
    }
    if (is_kd())
        accel::write_kd_file(path, structure.kd.tree, meta);
    else
        accel::write_tree_file(path, result.tree, meta);
}

std::optional<Layout> cpu_reference_layout(const std::string& name) {
    if (name == "plain") return Layout::kBvh2;   // traverse_bvh2
    if (name == "cwbvh") return Layout::kCwbvh;  // traverse_cwbvh
    return std::nullopt;
}

}  // namespace bvhlab::trav
