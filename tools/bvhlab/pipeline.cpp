// SPDX-License-Identifier: MIT
#include "tools/bvhlab/pipeline.h"

#include <algorithm>
#include <cstdio>
#include <optional>

#include "accel/builders/kdtree.h"
#include "accel/core/check.h"
#include "accel/core/validate.h"
#include "accel/io/tree_file.h"
#include "accel/layouts/bvh2_convert.h"
#include "accel/layouts/cwbvh_convert.h"
#include "accel/layouts/kd_convert.h"
#include "accel/passes/collapse_wide.h"
#include "traversal/device/kd_traverse.h"
#include "traversal/gpu/gpu_tracer.h"

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
        if (opts.layout_flag->count())
            throw Error("structure file '" + file + "' holds a kd-tree; --layout applies to BVHs");
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
    for (const CLI::Option* flag : opts.kd_flags)
        if (flag->count())
            throw Error("structure file '" + file + "' holds a BVH, but kd-tree option " + flag->get_name() +
                        " was given");
    if (opts.kd_stack_flag->count())
        throw Error("structure file '" + file + "' holds a BVH; --kd-stack applies to kd-trees");
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
        throw Error("stale structure file '" + file + "': it was built with " + have + ", but " + want +
                    " was asked for");
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
    b.structure.name = "kdtree";
    b.structure.layout = trav::Layout::kKd;
    b.structure.kd = accel::convert_to_kd_layout(std::move(tree), scene.mesh);
    b.record["layout_bytes"] = b.structure.bytes();
    if (cached) {
        b.record["structure_file"] = file;
        b.loaded_meta = cached->meta;
    }
    return b;
}

/// The bytes of the BVH2 layout of `tree` (nodes, Woop triangles, triangle ids), without
/// building it: what a CWBVH's bytes are compared with.
static size_t bvh2_layout_bytes(const accel::BuildTree& tree) {
    size_t interior = 0;
    for (const accel::BuildNode& n : tree.nodes) interior += !n.is_leaf();
    return std::max<size_t>(interior, 1) * sizeof(accel::Bvh2Node) +
           tree.prim_indices.size() * (sizeof(accel::WoopTriangle) + sizeof(uint32_t));
}

/// The CWBVH path of build_scene: collapse the binary tree to 8-wide, check it, quantise.
static void convert_cwbvh(const Scene& scene, const BuildOptions& opts, const Globals& g, Built& b) {
    const auto t0 = std::chrono::steady_clock::now();
    accel::WideTree w;
    {
        Stage st(g, "collapsing to an 8-wide BVH (" + opts.collapse + ") and quantising its boxes");
        w = accel::collapse_to_wide(
            b.result.tree, scene.mesh,
            opts.collapse == "greedy" ? accel::CollapseMethod::kGreedy : accel::CollapseMethod::kSahOptimal);
        const std::string err = accel::validate_wide(w, scene.mesh.triangle_count(), b.result.tree.prim_indices);
        BVHLAB_CHECK(err.empty(), "the collapse produced an invalid wide tree: " + err);
        b.structure.layout = trav::Layout::kCwbvh;
        b.structure.cwbvh = accel::convert_to_cwbvh(
            w, scene.mesh, opts.cw_tris == "vertices" ? accel::CwTris::kVertices : accel::CwTris::kWoop);
    }
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    const accel::WideStats ws = accel::compute_wide_stats(w);
    const size_t bvh2_bytes = bvh2_layout_bytes(b.result.tree);
    b.record["wide"] = {{"collapse", opts.collapse},
                        {"triangles", opts.cw_tris},
                        {"collapse_ms", ms},
                        {"nodes", ws.nodes},
                        {"leaves", ws.leaves},
                        {"references", ws.references},
                        {"mean_children", ws.mean_children},
                        {"sah", ws.sah},
                        {"sah_costs", {{"node", accel::WideCost{}.node}, {"prim", accel::WideCost{}.prim}}},
                        {"depth", ws.depth},
                        {"node_bytes", b.structure.cwbvh.nodes.size() * sizeof(accel::CwbvhNode)}};
    b.record["bvh2_layout_bytes"] = bvh2_bytes;
    b.record["bytes_vs_bvh2"] = double(b.structure.cwbvh.bytes()) / double(bvh2_bytes);
}

Built build_scene(const Scene& scene, const BuildOptions& opts_in, const Globals& g) {
    opts_in.check_applicable();
    if (opts_in.is_kdtree()) return build_kdtree(scene, opts_in, g, nullptr, "");
    Built b;
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
        Stage st(g, "building " + opts.builder + " SAH BVH over " + std::to_string(scene.mesh.triangle_count()) +
                        " triangles");
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
    b.record = base_record("build", scene);
    b.record.update(stats_json(b.stats, b.result, builder, scene.mesh));
    if (opts.is_cwbvh()) {
        convert_cwbvh(scene, opts, g, b);
        // Woop triangles are the default and keep the plain name; vertex triples are named.
        b.structure.name = std::string(opts.cw_tris == "vertices" ? "cwbvh-vertices/" : "cwbvh/") + builder;
    } else {
        b.structure.name = "bvh2/" + builder;
        b.structure.layout = trav::Layout::kBvh2;
        b.structure.bvh2 = accel::convert_to_bvh2(b.result.tree, scene.mesh);
    }
    b.record["structure"] = b.structure.name;
    b.record["layout"] = trav::layout_name(b.structure.layout);
    b.record["layout_bytes"] = b.structure.bytes();
    b.record["layout_depth"] = b.structure.depth();
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

void TraceOptions::add_to(CLI::App& app, bool allow_embree) {
    std::vector<std::string> devices{"cpu", "gpu"};
    if (allow_embree) devices.push_back("embree");
    app.add_option("--device", device,
                   allow_embree
                       ? "cpu (TBB over the shared traversal), gpu (a CUDA kernel) or embree (Embree 3 on every "
                         "core: rtcIntersect1/rtcOccluded1 and the 16-wide packet calls, the faster reported)"
                       : "cpu (TBB over the shared traversal) or gpu (a CUDA kernel, see --kernel)")
        ->check(CLI::IsMember(devices))
        ->capture_default_str();
    kernel_flag = app.add_option(
        "--kernel", kernel,
        "GPU kernel (`bvhlab kernels` lists them) or all; on --device cpu, plain or cwbvh: the CPU "
        "runs that kernel's traversal; default: cwbvh for --layout cwbvh, dynamic-speculative-fma for BVHs, "
        "kd-full-stack or kd-short-stack (with --kd-stack 1..8) for kd-trees");
    block_flag = app.add_option("--block-size", block_size, "GPU threads per block (default: the kernel's)")
                     ->check(CLI::Range(32, 1024));
    fetch_flag = app.add_option("--fetch-threshold", fetch_threshold,
                                "dynamic-fetch kernels: idle lanes of a warp (1..32) that start new rays (default 8)")
                     ->check(CLI::Range(1, 32));
}

/// The layout whose CPU traversal is the one kernel `name` runs on the GPU (the CPU reference
/// behind `--device cpu --kernel NAME`).
static std::optional<trav::Layout> cpu_reference_layout(const std::string& name) {
    if (name == "plain") return trav::Layout::kBvh2;   // traverse_bvh2
    if (name == "cwbvh") return trav::Layout::kCwbvh;  // traverse_cwbvh
    return std::nullopt;
}

void TraceOptions::validate(BuildOptions& build) const {
    // --kernel picks the layout it traces, unless --layout says otherwise.
    if (kernel_flag->count() && kernel != "all" && device != "embree") {
        trav::Layout layout;
        if (device == "cpu") {
            const auto l = cpu_reference_layout(kernel);
            if (!l)
                throw Error("--kernel " + kernel +
                            " has no CPU form: it needs --device gpu (on the CPU, --kernel takes "
                            "plain or cwbvh, whose traversals the CPU runs)");
            layout = *l;
        } else {
            layout = trav::find_kernel(kernel).layout;
        }
        if (layout == trav::Layout::kCwbvh) {
            if (build.is_kdtree())
                throw Error("kernel '" + kernel + "' traces a CWBVH, which is built from a BVH, not a kd-tree");
            if (build.layout_flag->count() && !build.is_cwbvh())
                throw Error("kernel '" + kernel + "' traces --layout cwbvh, not --layout " + build.layout);
            build.layout = "cwbvh";
        } else if (layout == trav::Layout::kBvh2 && build.is_cwbvh() && !build.is_kdtree()) {
            throw Error("kernel '" + kernel + "' traces --layout bvh2, not --layout cwbvh");
        }
    }
    if (device != "gpu") {
        if (kernel_flag->count() && (device != "cpu" || kernel == "all"))
            throw Error("--kernel " + kernel + " chooses GPU kernels; it needs --device gpu");
        if (block_flag->count()) throw Error("--block-size applies to GPU kernels; it needs --device gpu");
        if (fetch_flag->count()) throw Error("--fetch-threshold applies to GPU kernels; it needs --device gpu");
    }
    if (device == "embree") {
        std::vector<const CLI::Option*> flags{build.structure_flag, build.builder_flag,  build.kd_stack_flag,
                                              build.layout_flag,    build.collapse_flag, build.cw_tris_flag};
        flags.insert(flags.end(), build.config_flags.begin(), build.config_flags.end());
        flags.insert(flags.end(), build.kd_flags.begin(), build.kd_flags.end());
        for (const CLI::Option* f : flags)
            if (f->count())
                throw Error(f->get_name() + " does not apply to --device embree (Embree builds its own BVH)");
    }
    if (device == "gpu") {
        std::string why;
        if (!trav::gpu_available(&why)) throw Error("--device gpu: " + why);
    }
}

namespace {

/// The default GPU kernel of a structure: the fastest BVH2 kernel as measured on the H100 (the
/// best on every diffuse set and on furball; within 4% of while-while-fma on primary rays)
/// (experiments/NOTES.md), or the kd kernel that matches --kd-stack.
std::string default_kernel(const Built& b, int kd_stack) {
    if (b.structure.layout == trav::Layout::kCwbvh) return "cwbvh";
    if (!b.is_kd()) return "dynamic-speculative-fma";
    return kd_stack == trav::kKdFullStack ? "kd-full-stack" : "kd-short-stack";
}

}  // namespace

std::vector<std::unique_ptr<trav::Tracer>> make_tracers(Built& built, const TraceOptions& t, const BuildOptions& b,
                                                        const trav::EmbreeOracle* oracle) {
    std::vector<std::unique_ptr<trav::Tracer>> out;
    if (t.device == "cpu") {
        out.push_back(trav::make_cpu_tracer(built.structure, b.kd_stack));
        return out;
    }
    if (t.device == "embree") {
        BVHLAB_CHECK(oracle != nullptr, "an Embree tracer needs the oracle");
        out.push_back(trav::make_embree_tracer(*oracle, false));
        out.push_back(trav::make_embree_tracer(*oracle, true));
        return out;
    }
    std::vector<trav::KernelInfo> kernels;
    if (t.kernel == "all") {
        for (const trav::KernelInfo& k : trav::registered_kernels())
            if (k.layout == built.structure.layout) kernels.push_back(k);
    } else {
        kernels.push_back(trav::find_kernel(t.kernel.empty() ? default_kernel(built, b.kd_stack) : t.kernel));
    }
    // Each kernel's options, checked before anything is uploaded: --kd-stack 1..8 sizes a short
    // stack (a full-stack kernel takes none), and with --kernel all --fetch-threshold goes to
    // the dynamic-fetch kernels among them.
    const bool all = t.kernel == "all";
    const bool short_given = b.kd_stack_flag->count() && b.kd_stack != trav::kKdFullStack;
    std::vector<trav::GpuTraceOptions> options;
    for (const trav::KernelInfo& k : kernels) {
        trav::GpuTraceOptions o;
        o.block_size = t.block_size;
        o.fetch_threshold = all && !k.dynamic_fetch ? 0 : t.fetch_threshold;
        if (short_given) o.kd_stack = b.kd_stack;
        trav::check_kernel_fits(k, built.structure.layout, built.structure.depth(), o);
        if (!all && short_given && !k.short_stack)
            throw Error(std::string("--kd-stack ") + std::to_string(b.kd_stack) + " sizes a short stack; kernel '" +
                        k.name + "' has a full stack (use kd-short-stack)");
        if (b.kd_stack_flag->count() && !short_given && k.short_stack)
            throw Error(std::string("kernel '") + k.name +
                        "' takes a short stack of 1..8 entries (--kd-stack), not 64");
        options.push_back(o);
    }
    if (!built.device) built.device = std::make_shared<trav::DeviceStructure>(built.structure);
    for (size_t i = 0; i < kernels.size(); ++i)
        out.push_back(trav::make_gpu_tracer(built.device, kernels[i], options[i]));
    return out;
}

CheckedSet check_set(const trav::EmbreeOracle& oracle, const trav::RaySet& set, const std::string& ray_type) {
    CheckedSet cs{set, ray_type, {}};
    oracle.trace(set.rays, set.query, cs.reference);
    return cs;
}

nlohmann::json tracer_fields(const Built& built, const trav::Tracer& tracer) {
    const std::string device = tracer.device();
    const bool gpu = device == "gpu", embree = device == "embree";
    return {{"device", device},
            {"structure", embree ? std::string("embree/robust-high") : built.structure.name},
            {"layout", embree ? "embree" : trav::layout_name(built.structure.layout)},
            {"kernel", tracer.name()},
            {"block_size", gpu ? nlohmann::json(tracer.block_size()) : nlohmann::json(nullptr)},
            {"short_stack", tracer.short_stack() ? nlohmann::json(tracer.short_stack()) : nlohmann::json(nullptr)},
            {"fetch_threshold",
             tracer.fetch_threshold() ? nlohmann::json(tracer.fetch_threshold()) : nlohmann::json(nullptr)},
            {"gpu", gpu ? nlohmann::json(trav::gpu_description()) : nlohmann::json(nullptr)},
            {"driver", gpu ? nlohmann::json(trav::gpu_driver()) : nlohmann::json(nullptr)}};
}

nlohmann::json verify_hits(const Scene& scene, const trav::EmbreeOracle& oracle, const CheckedSet& cs,
                           const std::vector<trav::Hit>& ours, const trav::CompareConfig& cc) {
    trav::CompareReport rep = trav::compare_hits(
        scene.mesh, cs.set.rays, cs.set.query, ours, cs.reference,
        [&](const trav::Ray& r) { return oracle.intersect(r); }, cc);
    for (const auto& d : rep.first_mismatches) {
        std::fprintf(stderr, "[bvhlab] MISMATCH %s ray %zu: ours tri %d t %.9g, embree tri %d t %.9g: %s\n",
                     cs.ray_type.c_str(), d.ray, d.ours.tri, d.ours.t, d.oracle.tri, d.oracle.t, d.reason.c_str());
    }
    nlohmann::json j = base_record("verify", scene);
    j["ray_type"] = cs.ray_type;
    j["query"] = cs.set.query == trav::Query::kAny ? "any" : "closest";
    j["rays"] = rep.rays;
    j["agree"] = rep.agree;
    j["ties"] = rep.ties;
    j["ties_shared_edge"] = rep.ties_by_kind[size_t(trav::TieKind::kSharedEdgeOrVertex)];
    j["ties_near_edge"] = rep.ties_by_kind[size_t(trav::TieKind::kNearEdge)];
    j["ties_interval_end"] = rep.ties_by_kind[size_t(trav::TieKind::kIntervalEnd)];
    j["ties_coincident"] = rep.ties_by_kind[size_t(trav::TieKind::kCoincident)];
    j["mismatches"] = rep.mismatches;
    nlohmann::json kinds = nlohmann::json::object();
    for (int k = 0; k < trav::kMismatchKinds; ++k)
        kinds[trav::mismatch_kind_name(trav::MismatchKind(k))] = rep.mismatches_by_kind[size_t(k)];
    j["mismatch_kinds"] = kinds;
    j["max_rel_dt"] = rep.max_rel_dt;
    j["edge_eps"] = cc.edge_eps;
    j["t_rel_tol"] = cc.t_rel_tol;
    return j;
}

nlohmann::json work_per_ray(const Built& built, int kd_stack, const trav::RaySet& set) {
    std::vector<trav::Hit> hits;
    std::vector<trav::TraversalCounters> c;
    trav::trace_cpu_counted(built.structure, kd_stack, set, hits, &c);
    double nodes = 0, leaves = 0, tris = 0, restarts = 0;
    for (const auto& x : c) {
        nodes += x.nodes;
        leaves += x.leaves;
        tris += x.tri_tests;
        restarts += x.restarts;
    }
    const double n = c.empty() ? 1.0 : double(c.size());
    return {{"nodes", nodes / n}, {"leaves", leaves / n}, {"tri_tests", tris / n}, {"restarts", restarts / n}};
}

nlohmann::json bench_ray_set(const Scene& scene, const Built& built, trav::Tracer& tracer,
                             const trav::EmbreeOracle& oracle, const CheckedSet& cs, const BenchSettings& bs,
                             const trav::CompareConfig& cc, const Globals& g, std::vector<trav::Hit>* hits_out,
                             nlohmann::json* verify_record) {
    const std::string device = tracer.device();
    const bool gpu = device == "gpu";
    nlohmann::json j = base_record("bench", scene);
    j["ray_type"] = cs.ray_type;
    j["query"] = cs.set.query == trav::Query::kAny ? "any" : "closest";
    j["rays"] = cs.set.rays.size();
    const nlohmann::json fields = tracer_fields(built, tracer);
    j.update(fields);
    j["machine"] = machine_description();
    std::vector<trav::Hit> hits;
    Stage st(g, tracer.name() + ": " + std::to_string(cs.set.rays.size()) + " " + cs.ray_type + " rays on " + device +
                    " (check against Embree, " + std::to_string(bs.warmup) + " warm-up, " + std::to_string(bs.runs) +
                    " runs)");
    // Check before timing: a tracer that disagrees with Embree is reported, never timed.
    tracer.set_rays(cs.set.rays, cs.set.query);
    tracer.run();
    tracer.hits(hits);
    trav::CompareConfig check_cc = cc;
    check_cc.any_hit_flags = device == "embree";  // rtcOccluded names no triangle
    nlohmann::json check = verify_hits(scene, oracle, cs, hits, check_cc);
    check.update(fields);
    if (verify_record) *verify_record = check;
    j["check"] = {{"mismatches", check["mismatches"]}, {"ties", check["ties"]}};
    if (check["mismatches"].get<size_t>() > 0) {
        j["status"] = "failed";
        j["mrays_per_s"] = nullptr;
        if (hits_out) *hits_out = std::move(hits);
        return j;
    }
    std::vector<double> ms;
    for (int i = 0; i < bs.warmup + bs.runs; ++i) {
        const double t = tracer.run();
        if (i >= bs.warmup) ms.push_back(t);
        st.progress(size_t(i + 1), size_t(bs.warmup + bs.runs));
    }
    tracer.hits(hits);
    std::sort(ms.begin(), ms.end());
    const double median = ms.size() % 2 ? ms[ms.size() / 2] : 0.5 * (ms[ms.size() / 2 - 1] + ms[ms.size() / 2]);
    size_t nhit = 0;
    for (const auto& h : hits) nhit += h.is_hit();
    j["status"] = "ok";
    j["hit_fraction"] = cs.set.rays.empty() ? 0.0 : double(nhit) / double(cs.set.rays.size());
    j["runs"] = bs.runs;
    j["warmup"] = bs.warmup;
    j["median_ms"] = median;
    j["min_ms"] = ms.front();
    j["max_ms"] = ms.back();
    j["mrays_per_s"] = median > 0 ? double(cs.set.rays.size()) / (median * 1e3) : 0.0;
    j["timing"] = gpu ? "kernel only (CUDA events)" : "wall clock of the parallel trace";
    if (gpu) {
        const trav::SmClock clk = trav::gpu_sm_clock();
        j["sm_clock_mhz"] = clk.current_mhz ? nlohmann::json(clk.current_mhz) : nlohmann::json(nullptr);
        j["sm_clock_max_mhz"] = clk.max_mhz;
    }
    if (hits_out) *hits_out = std::move(hits);
    return j;
}

void add_compare_options(CLI::App& app, trav::CompareConfig& cc) {
    app.add_option("--edge-eps", cc.edge_eps, "barycentric distance from an edge that counts as a tie")
        ->check(FiniteRange(0.0, 0.1))
        ->capture_default_str();
    app.add_option("--t-tol", cc.t_rel_tol, "relative t difference under which two hits are at the same t")
        ->check(FiniteRange(0.0, 0.1))
        ->capture_default_str();
}

}  // namespace bvhlab::cli
