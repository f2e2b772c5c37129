// SPDX-License-Identifier: MIT
// `bvhlab bench`: traversal speed in Mrays/s, the median of N runs after warm-up.
#include <cstdio>
#include <memory>

#include "accel/core/check.h"
#include "tools/bvhlab/commands.h"
#include "tools/bvhlab/pipeline.h"
#include "traversal/rays/ray_file.h"

namespace bvhlab::cli {

void print_bench_row(const nlohmann::json& j) {
    std::printf("%-10s %12zu rays  %9.2f Mrays/s  (median of %d, %.1f ms; %s, %s)\n",
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
    };
    auto o = std::make_shared<Opts>();
    CLI::App* sub = app.add_subcommand("bench", "benchmark traversal in Mrays/s on protocol rays or a ray file");
    sub->add_option("scene", o->scene, "OBJ file, scene name from scenes.json, or gen:KIND:N[:SEED]")->required();
    auto* types = sub->add_option("--types", o->types, "comma-separated ray types, or all")->capture_default_str();
    auto* file = sub->add_option("--rays", o->rays_file, "trace this ray file instead of protocol rays")->check(CLI::ExistingFile);
    file->excludes(types);
    auto* hits = sub->add_option("--hits-out", o->hits_out, "write the hits of the last run (needs --rays)");
    hits->needs(file);
    sub->add_option("--runs", o->bench.runs, "timed runs (the median is reported)")->check(CLI::Range(1, 1000))->capture_default_str();
    sub->add_option("--warmup", o->bench.warmup, "untimed warm-up runs")->check(CLI::Range(0, 100))->capture_default_str();
    add_device_option(*sub, o->bench.device);
    o->build.add_to(*sub);
    o->rays.add_to(*sub);
    sub->callback([o, &g, file] {
        std::string why;
        if (o->bench.device == "gpu" && !trav::gpu_available(&why)) throw Error("--device gpu: " + why);
        Scene s = load_scene(o->scene, g);
        o->build.epo = false;  // EPO is a build figure; bench does not need it
        Built b = build_scene(s, o->build, g);
        auto report = [&](const nlohmann::json& j) { if (g.json) emit(j); else print_bench_row(j); };
        if (file->count()) {
            trav::RaySet set = trav::read_ray_file(o->rays_file);
            std::vector<trav::Hit> hits;
            nlohmann::json j = bench_ray_set(s, b, set, "file", o->bench, g, &hits);
            j["ray_file"] = o->rays_file;
            report(j);
            if (!o->hits_out.empty()) trav::write_hit_file(o->hits_out, {hits, set.query});
            return;
        }
        const auto types = parse_ray_types(o->types);
        trav::EmbreeOracle oracle(s.mesh);
        trav::RayProtocol proto(s.mesh, oracle, o->rays.for_scene(s));
        const nlohmann::json protocol = protocol_json(o->rays.for_scene(s));
        for (trav::RayType t : types) {
            nlohmann::json j = bench_ray_set(s, b, proto.make(t), trav::ray_type_name(t), o->bench, g);
            j["protocol"] = protocol;
            report(j);
        }
    });
}

}  // namespace bvhlab::cli
