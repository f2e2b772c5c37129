// SPDX-License-Identifier: MIT
#include "tools/bvhlab/pipeline.h"

#include <sys/resource.h>

#include <algorithm>
#include <cstdio>
#include <optional>

#include "accel/core/check.h"
#include "accel/io/tree_file.h"
#include "traversal/device/kd_traverse.h"
#include "traversal/gpu/gpu_tracer.h"

namespace bvhlab::cli {

/// Checks a structure file read from disk against the options given explicitly on the command
/// line (everything not given comes from the file); the scene check is the factory's.
static void check_explicit_options(const BuildOptions& opts, const accel::TreeFile& f, const std::string& file) {
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
        return;
    }
    for (const CLI::Option* flag : opts.kd_flags)
        if (flag->count())
            throw Error("structure file '" + file + "' holds a BVH, but kd-tree option " + flag->get_name() +
                        " was given");
    if (opts.kd_stack_flag->count())
        throw Error("structure file '" + file + "' holds a BVH; --kd-stack applies to kd-trees");
    accel::BuilderOptions asked = f.meta.options;
    const accel::BuilderOptions& given = opts.opts;
    const CLI::Option* const* flags = opts.config_flags.data();
    if (flags[0]->count()) asked.num_bins = given.num_bins;
    if (flags[1]->count()) asked.config.max_leaf_size = given.config.max_leaf_size;
    if (flags[2]->count()) asked.config.min_leaf_size = given.config.min_leaf_size;
    if (flags[3]->count()) asked.sbvh_alpha = given.sbvh_alpha;
    if (flags[4]->count()) asked.sbvh_budget = given.sbvh_budget;
    if (flags[5]->count()) asked.sbvh_spatial_bins = given.sbvh_spatial_bins;
    if (flags[6]->count()) asked.reinsertion_passes = given.reinsertion_passes;
    if (flags[7]->count()) asked.morton_bits = given.morton_bits;
    if (flags[8]->count()) asked.ploc_radius = given.ploc_radius;
    if (flags[9]->count()) asked.cluster_alpha = given.cluster_alpha;
    const std::string have = accel::describe_config(f.meta.builder, f.meta.options);
    const std::string want = accel::describe_config(f.meta.builder, asked);
    if (have != want)
        throw Error("stale structure file '" + file + "': it was built with " + have + ", but " + want +
                    " was asked for");
}

Built build_scene(const Scene& scene, const BuildOptions& opts, const Globals& g) {
    opts.check_applicable();
    const trav::StageHook stage = [&g](const std::string& what) { return std::make_shared<Stage>(g, what); };
    const std::string file = opts.structure_file();
    Built b;
    if (file.empty() && scene.placed) {
        static_cast<trav::AccelStructure&>(b) = trav::build_structure(*scene.placed, opts.spec(), stage);
    } else if (file.empty()) {
        static_cast<trav::AccelStructure&>(b) = trav::build_structure(scene.mesh, opts.spec(), stage);
    } else if (scene.placed) {
        throw Error("structure files hold single-level structures and scene '" + scene.name +
                    "' places a mesh more than once: --flatten makes it one mesh");
    } else {
        accel::TreeFile f;
        {
            Stage st(g, "loading structure " + file);
            f = accel::read_tree_file(file);
        }
        check_explicit_options(opts, f, file);
        static_cast<trav::AccelStructure&>(b) =
            trav::structure_from_file(scene.mesh, scene.hash, std::move(f), file, opts.spec(), stage);
    }
    if (!b.stats.epo_skipped.empty() && !g.quiet)
        std::fprintf(stderr, "[bvhlab] warning: %s\n", b.stats.epo_skipped.c_str());
    b.record = base_record("build", scene);
    b.record.update(b.figures);
    // Memory: the layout's bytes per (world) triangle, and the process's peak resident set so
    // far (scene, structure and every temporary; Linux reports kilobytes).
    const uint64_t triangles = b.record.value("triangles", uint64_t(0));
    b.record["bytes_per_triangle"] = triangles ? double(b.structure.bytes()) / double(triangles) : 0.0;
    struct rusage ru {};
    if (getrusage(RUSAGE_SELF, &ru) == 0) b.record["peak_host_bytes"] = uint64_t(ru.ru_maxrss) * 1024u;
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

void TraceOptions::validate(BuildOptions& build) const {
    // --kernel picks the layout it traces, unless --layout says otherwise.
    if (kernel_flag->count() && kernel != "all" && device != "embree") {
        trav::Layout layout;
        if (device == "cpu") {
            const auto l = trav::cpu_reference_layout(kernel);
            if (!l)
                throw Error("--kernel " + kernel +
                            " has no CPU form: it needs --device gpu (on the CPU, --kernel takes "
                            "plain or cwbvh, whose traversals the CPU runs)");
            layout = *l;
        } else {
            layout = trav::find_kernel(kernel).layout;
        }
        const bool wide = layout == trav::Layout::kCwbvh || layout == trav::Layout::kTwoLevelCwbvh;
        if (wide) {
            if (build.is_kdtree())
                throw Error("kernel '" + kernel + "' traces a CWBVH, which is built from a BVH, not a kd-tree");
            if (build.layout_flag->count() && !build.is_cwbvh())
                throw Error("kernel '" + kernel + "' traces --layout cwbvh, not --layout " + build.layout);
            build.layout = "cwbvh";
        } else if ((layout == trav::Layout::kBvh2 || layout == trav::Layout::kTwoLevel) && build.is_cwbvh() &&
                   !build.is_kdtree()) {
            throw Error("kernel '" + kernel + "' traces --layout bvh2, not --layout cwbvh");
        }
    }
    if (device != "gpu") {
        if (kernel_flag->count() && (device != "cpu" || kernel == "all"))
            throw Error("--kernel " + kernel + " chooses GPU kernels; it needs --device gpu");
        if (block_flag->count()) throw Error("--block-size applies to GPU kernels; it needs --device gpu");
        if (fetch_flag->count()) throw Error("--fetch-threshold applies to GPU kernels; it needs --device gpu");
    }
    if (device == "embree")
        if (const CLI::Option* f = given_structure_flag(build))
            throw Error(f->get_name() + " does not apply to --device embree (Embree builds its own BVH)");
    if (device == "gpu") {
        std::string why;
        if (!trav::gpu_available(&why)) throw Error("--device gpu: " + why);
    }
}

const CLI::Option* given_structure_flag(const BuildOptions& build) {
    std::vector<const CLI::Option*> flags{build.structure_flag,   build.builder_flag,  build.kd_stack_flag,
                                          build.layout_flag,      build.collapse_flag, build.cw_tris_flag,
                                          build.build_device_flag};
    flags.insert(flags.end(), build.config_flags.begin(), build.config_flags.end());
    flags.insert(flags.end(), build.kd_flags.begin(), build.kd_flags.end());
    for (const CLI::Option* f : flags)
        if (f && f->count()) return f;
    return nullptr;
}

std::vector<std::unique_ptr<trav::Tracer>> make_tracers(Built& built, const TraceOptions& t, const BuildOptions& b,
                                                        const trav::EmbreeOracle* oracle) {
    std::vector<std::unique_ptr<trav::Tracer>> out;
    if (t.device == "cpu") {
        out.push_back(built.cpu_tracer());
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
        kernels.push_back(t.kernel.empty() ? built.default_kernel() : trav::find_kernel(t.kernel));
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
    for (size_t i = 0; i < kernels.size(); ++i)
        out.push_back(trav::make_gpu_tracer(built.device(), kernels[i], options[i]));
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
    return {
        {"device", device},
        {"structure", embree ? std::string("embree/robust-high") : built.structure.name},
        {"layout", embree ? "embree" : trav::layout_name(built.structure.layout)},
        {"kernel", tracer.name()},
        {"block_size", gpu ? nlohmann::json(tracer.block_size()) : nlohmann::json(nullptr)},
        {"short_stack", tracer.short_stack() ? nlohmann::json(tracer.short_stack()) : nlohmann::json(nullptr)},
        {"fetch_threshold",
         tracer.fetch_threshold() ? nlohmann::json(tracer.fetch_threshold()) : nlohmann::json(nullptr)},
        {"gpu", gpu ? nlohmann::json(trav::gpu_description()) : nlohmann::json(nullptr)},
        {"driver", gpu ? nlohmann::json(trav::gpu_driver()) : nlohmann::json(nullptr)},
        // The structure's whole configuration (builder, leaf sizes, costs, bins or Morton bits, ...)
        // and, for a GPU builder, its build times: a bench or verify line names what it traced.
        {"config", embree ? nlohmann::json(nullptr) : built.figures.value("config", nlohmann::json(nullptr))},
        {"gpu_build", embree ? nlohmann::json(nullptr) : built.figures.value("gpu_build", nlohmann::json(nullptr))}};
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
    j.update(trav::report_json(rep, cc));
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
        // Device memory: the structure's upload, and the most this process has held (structure,
        // ray queue and hits; the CUDA context not included).
        if (const auto d = built.uploaded()) j["device_structure_bytes"] = d->bytes();
        j["device_peak_bytes"] = trav::gpu_memory_use().peak;
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
