// SPDX-License-Identifier: MIT
// `bvhlab bench`: traversal speed in Mrays/s, the median of N runs after warm-up, for one
// tracer or every GPU kernel (--kernel all), each checked against Embree before it is timed.
#include <cstdio>
#include <map>
#include <memory>

#include "accel/core/check.h"
#include "scene/io/atomic_file.h"
#include "tools/bvhlab/commands.h"
#include "tools/bvhlab/pipeline.h"
#include "traversal/rays/ray_file.h"

namespace bvhlab::cli {

void print_bench_row(const nlohmann::json& j) {
    if (j["status"] != "ok") {
        std::printf("%-10s %12zu rays  FAILED: %zu real mismatches against Embree, not timed  (%s, %s)\n",
                    j["ray_type"].get<std::string>().c_str(), j["rays"].get<size_t>(),
                    j["check"]["mismatches"].get<size_t>(), j["structure"].get<std::string>().c_str(),
                    j["kernel"].get<std::string>().c_str());
        return;
    }
    std::printf("%-10s %12zu rays  %9.2f Mrays/s  (median of %d, %.3f ms; %s, %s)\n",
                j["ray_type"].get<std::string>().c_str(), j["rays"].get<size_t>(), j["mrays_per_s"].get<double>(),
                j["runs"].get<int>(), j["median_ms"].get<double>(), j["structure"].get<std::string>().c_str(),
                j["kernel"].get<std::string>().c_str());
}

void register_bench(CLI::App& app, Globals& g) {
    struct Opts {
        std::string scene, types = "all", rays_file, hits_out;
        BuildOptions build;
        RayOptions rays;
        BenchSettings bench;
        TraceOptions trace;
        trav::CompareConfig cc;
    };
    auto o = std::make_shared<Opts>();
    CLI::App* sub = app.add_subcommand(
        "bench", "benchmark traversal in Mrays/s on protocol rays or a ray file (hits checked against Embree first)");
    sub->add_option("scene", o->scene, kSceneHelp)->required();
    auto* types = sub->add_option("--types", o->types, "comma-separated ray types, or all")->capture_default_str();
    auto* file = sub->add_option("--rays", o->rays_file, "trace this ray file instead of protocol rays")
                     ->check(CLI::ExistingFile);
    file->excludes(types);
    auto* hits = sub->add_option("--hits-out", o->hits_out, "write the hits of the last run (needs --rays)");
    hits->needs(file);
    auto* runs =
        sub->add_option("--runs", o->bench.runs, "timed runs, the median is reported (default 10; 5 on the cpu)")
            ->check(CLI::Range(1, 1000));
    sub->add_option("--warmup", o->bench.warmup, "untimed warm-up runs after the checked run")
        ->check(CLI::Range(0, 100))
        ->capture_default_str();
    o->trace.add_to(*sub, true);
    o->build.add_to(*sub);
    o->rays.add_to(*sub);
    o->rays.excluded_by(file);  // a ray file's rays are fixed: no protocol option applies
    add_compare_options(*sub, o->cc);
    sub->callback([o, &g, file, runs] {
        o->trace.validate(o->build);
        if (o->rays_file.empty()) o->rays.check_types(parse_ray_types(o->types), o->types);
        if (!runs->count()) o->bench.runs = o->trace.device == "cpu" ? 5 : 10;
        if (!o->hits_out.empty() && o->trace.kernel == "all")
            throw Error("--hits-out writes one tracer's hits; name one --kernel, not all");
        const std::vector<scene::NamedFile> outputs{{"--hits-out", o->hits_out}};
        std::vector<scene::NamedFile> inputs{
            {"the scene", o->scene}, {"--rays", o->rays_file}, {"--structure", o->build.structure_file()}};
        scene::refuse_clashing_files(outputs, inputs);  // before the load, and again with its files
        Scene s = load_scene(o->scene, g);
        for (auto& f : s.input_files()) inputs.push_back(std::move(f));
        scene::refuse_clashing_files(outputs, inputs);
        o->build.epo = false;  // EPO is a build figure; bench does not need it
        const std::unique_ptr<trav::EmbreeOracle> oracle_owner = make_oracle(s);
        const trav::EmbreeOracle& oracle = *oracle_owner;
        Built b;
        if (o->trace.device != "embree") b = build_scene(s, o->build, g);
        auto tracers = make_tracers(b, o->trace, o->build, &oracle);
        if (!o->hits_out.empty() && tracers.size() != 1)
            throw Error("--hits-out writes one tracer's hits; --device embree runs two");
        auto report = [&](const nlohmann::json& j) {
            if (g.json)
                emit(j);
            else
                print_bench_row(j);
            if (j["status"] != "ok") g_exit_code = 1;
        };
        const bool from_file = file->count() > 0;
        auto bench_set = [&](const trav::RaySet& set, const std::string& type, const nlohmann::json& protocol,
                             std::vector<trav::Hit>* hits_out) {
            const CheckedSet cs = check_set(oracle, set, type);
            std::map<int, nlohmann::json> work;  // by kd stack size; the GPU runs' per-ray work
            for (auto& t : tracers) {
                nlohmann::json j = bench_ray_set(s, b, *t, oracle, cs, o->bench, o->cc, g, hits_out);
                if (t->device() == "gpu") {
                    const int stack = t->short_stack() ? t->short_stack() : 64;
                    if (!work.count(stack)) work[stack] = work_per_ray(b, stack, set);
                    j["work_per_ray"] = work[stack];
                    j["work_counted_by"] = "the structure's shared traversal on the CPU, same rays";
                }
                if (!protocol.is_null()) j["protocol"] = protocol;
                if (from_file) {
                    j["ray_file"] = o->rays_file;
                    j["ray_file_hash"] = file_hash(o->rays_file);
                }
                report(j);
            }
        };
        if (from_file) {
            const trav::RaySet set = read_rays_for(o->rays_file, "bench");
            std::vector<trav::Hit> out;
            bench_set(set, "file", nullptr, &out);
            if (!o->hits_out.empty()) trav::write_hit_file(o->hits_out, {out, set.query, git_commit()}, s.first_ids);
            return;
        }
        trav::RayProtocol proto(s.mesh, oracle, o->rays.for_scene(s));
        const nlohmann::json protocol = protocol_json(o->rays.for_scene(s));
        for (trav::RayType t : parse_ray_types(o->types))
            bench_set(proto.make(t), trav::ray_type_name(t), protocol, nullptr);
        if (g_exit_code)
            std::fprintf(stderr, "bvhlab: error: a tracer disagrees with Embree and was not timed (see above)\n");
    });
}

}  // namespace bvhlab::cli
