// SPDX-License-Identifier: MIT
#include "tools/bvhlab/pipeline.h"

#include <algorithm>
#include <cstdio>

#include "accel/core/check.h"
#include "accel/builders/kdtree.h"
#include "traversal/device/kd_traverse.h"
#include "accel/core/validate.h"
#include "accel/io/tree_file.h"
#include "accel/layouts/bvh2_convert.h"
#include "traversal/cpu/cpu_trace.h"

namespace bvhlab::cli {

/// Loads a structure file and checks that it belongs to this scene and to the options given
/// explicitly on the command line.
static accel::TreeFile load_cached(const Scene& scene, const BuildOptions& opts, const std::string& file,
                                   const Globals& g) {
    Stage st(g, "loading structure " + file);
    accel::TreeFile f = accel::read_tree_file(file);
    const std::string stale = accel::stale_reason(f.meta, scene.mesh.triangle_count(), scene.hash);
    if (!stale.empty()) throw Error("stale structure file '" + file + "': " + stale);
    if (f.meta.kdtree) {
        for (const CLI::Option* flag : opts.config_flags)
            if (flag->count())
                throw Error("stale structure file '" + file + "': it holds a " + accel::describe_config(f.meta) +
                            ", but BVH option " + flag->get_name() + " was given");
        accel::TreeFileMeta asked = f.meta;
        if (opts.kd_flags[0]->count()) asked.kd.traversal_cost = opts.kd.traversal_cost;
        if (opts.kd_flags[1]->count()) asked.kd.intersection_cost = opts.kd.intersection_cost;
        if (opts.kd_flags[2]->count()) asked.kd.empty_bonus = opts.kd.empty_bonus;
        if (opts.kd_flags[3]->count()) asked.kd.max_depth = opts.kd.max_depth;
        if (accel::describe_config(asked) != accel::describe_config(f.meta))
            throw Error("stale structure file '" + file + "': it was built with " + accel::describe_config(f.meta) +
                        ", but " + accel::describe_config(asked) + " was asked for");
        return f;
    }
    accel::BuilderOptions asked = f.meta.options;
    const accel::BuilderOptions& given = opts.opts;
    // Only what the user said explicitly must match; everything else comes from the file.
    const CLI::Option* const* flags = opts.config_flags.data();
    if (flags[0]->count()) asked.num_bins = given.num_bins;
    if (flags[1]->count()) asked.config.max_leaf_size = given.config.max_leaf_size;
    if (flags[2]->count()) asked.config.min_leaf_size = given.config.min_leaf_size;
    if (flags[3]->count()) asked.sbvh_alpha = given.sbvh_alpha;
    if (flags[4]->count()) asked.sbvh_budget = given.sbvh_budget;
    if (flags[5]->count()) asked.sbvh_spatial_bins = given.sbvh_spatial_bins;
    if (flags[6]->count()) asked.reinsertion_passes = given.reinsertion_passes;
    const std::string have = accel::describe_config(f.meta.builder, f.meta.options);
    const std::string want = accel::describe_config(f.meta.builder, asked);
    if (have != want)
        throw Error("stale structure file '" + file + "': it was built with " + have + ", but " + want + " was asked for");
    return f;
}

/// The kd-tree path of build_scene: kd SAH and sizes (no EPO: it is a BVH figure). Uses the
/// tree of a loaded structure file when `cached` is given.
static Built build_kdtree(const Scene& scene, const BuildOptions& opts, const Globals& g, accel::TreeFile* cached,
                          const std::string& file) {
    Built b;
    accel::KdTreeBuilder builder(cached ? cached->meta.kd : opts.kd);
    accel::KdTree tree;
    if (cached) {
        tree = std::move(cached->kd);
        tree.bounds = scene.mesh.bounds();  // not stored: the scene hash guarantees the same box
    } else {
        Stage st(g, "building SAH kd-tree over " + std::to_string(scene.mesh.triangle_count()) + " triangles");
        const auto t0 = std::chrono::steady_clock::now();
        tree = builder.build(scene.mesh);
        b.result.build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    }
    const std::string err = accel::validate_kd(tree, scene.mesh.triangle_count());
    if (!err.empty())
        throw Error((cached ? "structure file '" + file + "' holds" : std::string("the kd-tree builder produced")) +
                    " an invalid kd-tree: " + err);
    const accel::KdTreeStats ks = accel::compute_kd_stats(tree, builder.config());
    b.structure = "kdtree";
    b.record = base_record("build", scene);
    b.record["builder"] = "kdtree";
    b.record["structure"] = "kdtree";
    b.record["nodes"] = ks.nodes;
    b.record["leaves"] = ks.leaves;
    b.record["depth"] = ks.depth;
    b.record["max_depth"] = builder.max_depth_for(scene.mesh.triangle_count());
    b.record["references"] = ks.references;
    b.record["mean_leaf_size"] = ks.leaves ? double(ks.references) / double(ks.leaves) : 0.0;
    b.record["max_leaf_size"] = ks.max_leaf_size;
    b.record["duplication"] = double(ks.references) / double(scene.mesh.triangle_count());
    b.record["bytes"] = tree.bytes();
    b.record["sah"] = ks.sah;
    b.record["sah_constants"] = {{"traversal", builder.config().traversal_cost},
                                 {"intersection", builder.config().intersection_cost},
                                 {"empty_bonus", builder.config().empty_bonus}};
    b.record["epo"] = nullptr;
    b.record["build_ms"] = b.result.build_ms;
    b.record["machine"] = machine_description();
    b.stats.sah = ks.sah;
    b.kd = std::make_shared<trav::KdTracer>(std::move(tree), scene.mesh, opts.kd_stack);
    b.kernel = opts.kd_stack == trav::kKdFullStack ? "cpu-kd-stack" : "cpu-kd-shortstack-" + std::to_string(opts.kd_stack);
    b.record["kernel"] = b.kernel;
    if (cached) {
        b.record["structure_file"] = file;
        b.loaded_meta = cached->meta;
    }
    return b;
}

Built build_scene(const Scene& scene, const BuildOptions& opts_in, const Globals& g) {
    if (opts_in.is_kdtree()) return build_kdtree(scene, opts_in, g, nullptr, "");
    Built b;
    b.kernel = "cpu-bvh2-stack";
    BuildOptions opts = opts_in;
    const std::string file = opts.structure_file();
    if (!file.empty()) {
        accel::TreeFile f = load_cached(scene, opts, file, g);
        if (f.meta.kdtree) return build_kdtree(scene, opts, g, &f, file);
        b.loaded_meta = f.meta;
        opts.builder = accel::builder_name(f.meta.builder);
        opts.opts = f.meta.options;
        b.result.tree = std::move(f.tree);
    } else {
        Stage st(g, "building " + opts.builder + " SAH BVH over " + std::to_string(scene.mesh.triangle_count()) + " triangles");
        b.result = accel::run_builder(opts.kind(), scene.mesh, opts.opts);
    }
    const std::string builder = opts.builder;
    accel::ValidateOptions vo;
    vo.allow_duplicates = opts.kind() == accel::BuilderKind::kSbvh;
    const std::string err = accel::validate(b.result.tree, scene.mesh, opts.opts.config, vo);
    if (!err.empty())
        throw Error((file.empty() ? "builder '" + builder + "' produced" : "structure file '" + file + "' holds") +
                    " an invalid tree: " + err);
    {
        Stage st(g, opts.epo ? "computing SAH and EPO" : "computing SAH");
        b.stats = accel::compute_stats(b.result.tree, scene.mesh, opts.opts.config, opts.epo);
    }
    b.bvh = accel::convert_to_bvh2(b.result.tree, scene.mesh);
    b.structure = "bvh2/" + builder;
    b.record = base_record("build", scene);
    b.record.update(stats_json(b.stats, b.result, builder, scene.mesh));
    b.record["structure"] = b.structure;
    b.record["layout_bytes"] = b.bvh.bytes();
    if (builder != "sweep") b.record["bins"] = opts.opts.num_bins;
    if (builder == "sbvh") {
        b.record["alpha"] = opts.opts.sbvh_alpha;
        b.record["budget"] = opts.opts.sbvh_budget;
    }
    b.record["max_leaf"] = opts.opts.config.max_leaf_size;
    b.record["reinsertion_passes"] = accel::reinsertion_passes(opts.kind(), opts.opts);
    b.record["config"] = accel::describe_config(opts.kind(), opts.opts);
    if (!file.empty()) b.record["structure_file"] = file;  // build_ms is then 0: nothing was built
    b.record["machine"] = machine_description();
    return b;
}

std::string kernel_name(const Built& built, const std::string& device) {
    return device == "gpu" ? "gpu-bvh2-stack-plain" : built.kernel;
}

void trace_cpu_any(const Built& built, const trav::RaySet& set, std::vector<trav::Hit>& hits,
                   std::vector<trav::TraversalCounters>* counters) {
    if (built.kd) {
        trav::trace_kd_cpu(*built.kd, set.rays, set.query, hits, counters);
    } else {
        trav::trace_cpu(built.bvh, set.rays, set.query, hits, counters);
    }
}

static trav::GpuBvh2& gpu_of(Built& built) {
    if (built.kd) throw Error("--device gpu: kd-trees have no GPU kernel yet; use --device cpu");
    if (!built.gpu) built.gpu = std::make_shared<trav::GpuBvh2>(built.bvh);
    return *built.gpu;
}

std::vector<trav::Hit> trace_on(Built& built, const trav::RaySet& set, const std::string& device) {
    std::vector<trav::Hit> hits;
    if (device == "gpu") {
        gpu_of(built).trace(set.rays, set.query, hits);
    } else {
        trace_cpu_any(built, set, hits);
    }
    return hits;
}

void add_device_option(CLI::App& app, std::string& device) {
    app.add_option("--device", device, "cpu (TBB, stack traversal) or gpu (CUDA, plain kernel)")
        ->check(CLI::IsMember({"cpu", "gpu"}))
        ->capture_default_str();
}

nlohmann::json bench_ray_set(const Scene& scene, Built& built, const trav::RaySet& set,
                             const std::string& ray_type, const BenchSettings& bs, const Globals& g,
                             std::vector<trav::Hit>* hits_out) {
    std::vector<trav::Hit> hits;
    std::vector<double> ms;
    const bool gpu = bs.device == "gpu";
    Stage st(g, "tracing " + std::to_string(set.rays.size()) + " " + ray_type + " rays on " + bs.device + " (" +
                    std::to_string(bs.warmup) + " warm-up + " + std::to_string(bs.runs) + " runs)");
    // GPU runs time the kernel alone (CUDA events); rays are uploaded once, outside the timing.
    if (gpu) gpu_of(built).upload_rays(set.rays);
    for (int i = 0; i < bs.warmup + bs.runs; ++i) {
        double t;
        if (gpu) {
            t = gpu_of(built).trace(set.query);
        } else {
            const auto t0 = std::chrono::steady_clock::now();
            trace_cpu_any(built, set, hits);
            t = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        }
        if (i >= bs.warmup) ms.push_back(t);
        st.progress(size_t(i + 1), size_t(bs.warmup + bs.runs));
    }
    if (gpu) gpu_of(built).download_hits(hits);
    std::sort(ms.begin(), ms.end());
    const double median = ms.size() % 2 ? ms[ms.size() / 2] : 0.5 * (ms[ms.size() / 2 - 1] + ms[ms.size() / 2]);
    size_t nhit = 0;
    for (const auto& h : hits) nhit += h.is_hit();
    nlohmann::json j = base_record("bench", scene);
    j["ray_type"] = ray_type;
    j["query"] = set.query == trav::Query::kAny ? "any" : "closest";
    j["rays"] = set.rays.size();
    j["hit_fraction"] = set.rays.empty() ? 0.0 : double(nhit) / double(set.rays.size());
    j["runs"] = bs.runs;
    j["median_ms"] = median;
    j["min_ms"] = ms.front();
    j["mrays_per_s"] = median > 0 ? double(set.rays.size()) / (median * 1e3) : 0.0;
    j["device"] = bs.device;
    j["gpu"] = gpu ? nlohmann::json(trav::gpu_description()) : nlohmann::json(nullptr);
    j["driver"] = gpu ? nlohmann::json(trav::gpu_driver()) : nlohmann::json(nullptr);
    j["structure"] = built.structure;
    j["kernel"] = kernel_name(built, bs.device);
    j["timing"] = gpu ? "kernel only (CUDA events)" : "wall clock of the parallel trace";
    j["machine"] = machine_description();
    if (hits_out) *hits_out = std::move(hits);
    return j;
}

nlohmann::json verify_ray_set(const Scene& scene, const trav::EmbreeOracle& oracle, const trav::RaySet& set,
                              const std::vector<trav::Hit>& ours, const std::string& ray_type,
                              const std::string& structure, const trav::CompareConfig& cc, const Globals& g,
                              const std::string& device, const std::string& kernel) {
    std::vector<trav::Hit> ref;
    trav::CompareReport rep;
    {
        Stage st(g, "verifying " + std::to_string(set.rays.size()) + " " + ray_type + " rays against Embree");
        oracle.trace(set.rays, set.query, ref);
        rep = trav::compare_hits(scene.mesh, set.rays, set.query, ours, ref,
                                 [&](const trav::Ray& r) { return oracle.intersect(r); }, cc);
    }
    for (const auto& d : rep.first_mismatches) {
        std::fprintf(stderr, "[bvhlab] MISMATCH %s ray %zu: ours tri %d t %.9g, embree tri %d t %.9g: %s\n",
                     ray_type.c_str(), d.ray, d.ours.tri, d.ours.t, d.oracle.tri, d.oracle.t, d.reason.c_str());
    }
    nlohmann::json j = base_record("verify", scene);
    j["ray_type"] = ray_type;
    j["query"] = set.query == trav::Query::kAny ? "any" : "closest";
    j["structure"] = structure;
    j["device"] = device;
    j["kernel"] = structure == "hit-file" ? "hit-file" : (device == "gpu" ? "gpu-bvh2-stack-plain" : kernel);
    j["rays"] = rep.rays;
    j["agree"] = rep.agree;
    j["ties"] = rep.ties;
    j["ties_shared_edge"] = rep.ties_by_kind[size_t(trav::TieKind::kSharedEdgeOrVertex)];
    j["ties_near_edge"] = rep.ties_by_kind[size_t(trav::TieKind::kNearEdge)];
    j["ties_interval_end"] = rep.ties_by_kind[size_t(trav::TieKind::kIntervalEnd)];
    j["ties_coincident"] = rep.ties_by_kind[size_t(trav::TieKind::kCoincident)];
    j["mismatches"] = rep.mismatches;
    j["max_rel_dt"] = rep.max_rel_dt;
    j["edge_eps"] = cc.edge_eps;
    j["t_rel_tol"] = cc.t_rel_tol;
    return j;
}

void add_compare_options(CLI::App& app, trav::CompareConfig& cc) {
    app.add_option("--edge-eps", cc.edge_eps, "barycentric distance from an edge that counts as a tie")
        ->check(CLI::Range(0.0, 0.1))
        ->capture_default_str();
    app.add_option("--t-tol", cc.t_rel_tol, "relative t difference under which two hits are at the same t")
        ->check(CLI::Range(0.0, 0.1))
        ->capture_default_str();
}

}  // namespace bvhlab::cli
