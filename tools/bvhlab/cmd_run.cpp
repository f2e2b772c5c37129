// SPDX-License-Identifier: MIT
// `bvhlab run`: the main job. For each scene: build, print quality figures, benchmark every
// ray type, verify every ray against Embree, then print one summary table.
#include <cstdio>
#include <filesystem>
#include <memory>

#include "accel/core/check.h"
#include "tools/bvhlab/commands.h"
#include "tools/bvhlab/pipeline.h"

namespace bvhlab::cli {

namespace fs = std::filesystem;

void print_bench_row(const nlohmann::json& j);
void print_verify_header();
void print_verify_row(const nlohmann::json& j);

void register_run(CLI::App& app, Globals& g) {
    struct Opts {
        std::vector<std::string> scenes;
        std::string types = "all";
        BuildOptions build;
        RayOptions rays;
        BenchSettings bench{3, 1};
        TraceOptions trace;
        trav::CompareConfig cc;
    };
    auto o = std::make_shared<Opts>();
    CLI::App* sub = app.add_subcommand(
        "run", "build, benchmark and verify: cornell-box plus every scene in $BVHLAB_SCENES unless scenes are given");
    sub->add_option("scenes", o->scenes, "scenes (OBJ files, catalogue names or gen: specs)");
    sub->add_option("--types", o->types, "comma-separated ray types, or all")->capture_default_str();
    sub->add_option("--runs", o->bench.runs, "timed runs per ray type")
        ->check(CLI::Range(1, 1000))
        ->capture_default_str();
    o->build.add_to(*sub);
    sub->add_flag("!--no-epo", o->build.epo, "skip EPO (slow on very large scenes)");
    o->rays.add_to(*sub);
    add_compare_options(*sub, o->cc);
    o->trace.add_to(*sub);
    sub->callback([o, &g] {
        o->trace.validate(o->build);
        std::vector<std::string> scenes = o->scenes;
        if (scenes.empty()) {
            scenes.push_back(data_dir() + "/cornell_box.obj");
            for (const auto& n : catalogue_scene_names()) scenes.push_back(n);
        }
        const auto types = parse_ray_types(o->types);
        struct Row {
            std::string scene;
            nlohmann::json build;
            std::vector<nlohmann::json> bench, verify;
        };
        std::vector<Row> rows;
        for (const auto& spec : scenes) {
            Scene s = load_scene(spec, g);
            Built b = build_scene(s, o->build, g);
            // Two scenes of one name (data/'s Cornell box and a catalogue's) are told apart by file.
            std::string name = s.name;
            for (const Row& r : rows)
                if (r.scene == name) name = s.name + " (" + fs::path(s.source).filename().string() + ")";
            Row row{name, b.record, {}, {}};
            if (g.json) emit(b.record);
            const std::unique_ptr<trav::EmbreeOracle> oracle_owner = make_oracle(s);
            const trav::EmbreeOracle& oracle = *oracle_owner;
            auto tracers = make_tracers(b, o->trace, o->build, &oracle);
            trav::RayProtocol proto(s.mesh, oracle, o->rays.for_scene(s));
            for (trav::RayType t : types) {
                const trav::RaySet set = proto.make(t);
                const CheckedSet cs = check_set(oracle, set, trav::ray_type_name(t));
                for (auto& tracer : tracers) {
                    nlohmann::json vj;
                    nlohmann::json bj = bench_ray_set(s, b, *tracer, oracle, cs, o->bench, o->cc, g, nullptr, &vj);
                    bj["protocol"] = vj["protocol"] = protocol_json(o->rays.for_scene(s));
                    if (g.json) {
                        emit(bj);
                        emit(vj);
                    }
                    if (vj["mismatches"].get<size_t>() > 0) g_exit_code = 1;
                    row.bench.push_back(bj);
                    row.verify.push_back(vj);
                }
            }
            if (!g.json) {
                std::printf("\n== %s ==\n", row.scene.c_str());
                print_build_table(s, b);
                std::printf("\n");
                for (const auto& j : row.bench) print_bench_row(j);
                std::printf("\n");
                print_verify_header();
                for (const auto& j : row.verify) print_verify_row(j);
                std::fflush(stdout);
            }
            rows.push_back(std::move(row));
        }
        if (!g.json) {
            std::printf("\n== summary (%s, %s build, commit %s) ==\n", machine_description().c_str(), build_type(),
                        git_commit());
            std::printf("%-24s %10s %8s %8s %9s", "scene", "triangles", "SAH", "EPO", "build ms");
            for (auto t : types) std::printf(" %10s", (std::string(trav::ray_type_name(t)) + " Mr/s").c_str());
            std::printf(" %10s\n", "mismatch");
            for (const auto& r : rows) {
                size_t mism = 0;
                for (const auto& v : r.verify) mism += v["mismatches"].get<size_t>();
                const double epo = r.build["epo"].is_null() ? -1.0 : r.build["epo"].get<double>();
                std::printf("%-24s %10zu %8.3f %8.3f %9.1f", r.scene.c_str(), r.build["triangles"].get<size_t>(),
                            r.build["sah"].get<double>(), epo, r.build["build_ms"].get<double>());
                for (const auto& bj : r.bench)
                    std::printf(" %10.2f", bj["status"] == "ok" ? bj["mrays_per_s"].get<double>() : 0.0);
                std::printf(" %10zu\n", mism);
            }
        }
        if (g_exit_code) std::fprintf(stderr, "bvhlab: error: real mismatches against Embree (see above)\n");
    });
}

}  // namespace bvhlab::cli
