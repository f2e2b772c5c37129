// SPDX-License-Identifier: MIT
// `bvhlab quality`: tree-quality figures (SAH, EPO, sizes) next to measured per-ray cost
// (nodes, leaves and triangle tests per ray: mean, p50, p99) for each ray type, so SAH and
// EPO can be set against what traversal really does.
#include <algorithm>
#include <cstdio>
#include <memory>

#include "tools/bvhlab/commands.h"
#include "tools/bvhlab/pipeline.h"
#include "traversal/tracer.h"

namespace bvhlab::cli {
namespace {

/// mean, p50 and p99 of one counter over all rays.
nlohmann::json distribution(std::vector<uint32_t> v) {
    if (v.empty()) return {{"mean", 0.0}, {"p50", 0}, {"p99", 0}};
    double sum = 0;
    for (uint32_t x : v) sum += x;
    auto pct = [&](double q) {
        const size_t k = std::min(v.size() - 1, size_t(q * double(v.size() - 1) + 0.5));
        std::nth_element(v.begin(), v.begin() + long(k), v.end());
        return v[k];
    };
    const uint32_t p50 = pct(0.50), p99 = pct(0.99);
    return {{"mean", sum / double(v.size())}, {"p50", p50}, {"p99", p99}};
}

}  // namespace

void register_quality(CLI::App& app, Globals& g) {
    struct Opts {
        std::string scene, types = "all";
        BuildOptions build;
        RayOptions rays;
    };
    auto o = std::make_shared<Opts>();
    CLI::App* sub = app.add_subcommand(
        "quality", "tree quality (SAH, EPO, sizes) and measured per-ray cost (nodes, leaves, triangle tests)");
    sub->add_option("scene", o->scene, kSceneHelp)->required();
    sub->add_option("--types", o->types, "comma-separated ray types, or all")->capture_default_str();
    o->build.add_to(*sub);
    sub->add_flag("!--no-epo", o->build.epo, "skip EPO (slow on very large scenes)");
    o->rays.add_to(*sub);
    sub->callback([o, &g] {
        o->rays.check_types(parse_ray_types(o->types), o->types);
        Scene s = load_scene(o->scene, g);
        Built b = build_scene(s, o->build, g);
        if (g.json)
            emit(b.record);
        else
            print_build_table(s, b);
        const std::unique_ptr<trav::EmbreeOracle> oracle_owner = make_oracle(s);
        const trav::EmbreeOracle& oracle = *oracle_owner;
        trav::RayProtocol proto(s.mesh, oracle, o->rays.for_scene(s));
        if (!g.json)
            std::printf("\n%-10s %10s   %-22s %-22s %-22s\n", "rays", "count", "nodes mean/p50/p99",
                        "leaves mean/p50/p99", "tri tests mean/p50/p99");
        for (trav::RayType t : parse_ray_types(o->types)) {
            const trav::RaySet set = proto.make(t);
            std::vector<trav::Hit> hits;
            std::vector<trav::TraversalCounters> c;
            {
                Stage st(g, std::string("counting traversal work of ") + trav::ray_type_name(t) + " rays");
                trav::trace_cpu_counted(b.structure, o->build.kd_stack, set, hits, &c);
            }
            std::vector<uint32_t> nodes(c.size()), leaves(c.size()), tris(c.size());
            for (size_t i = 0; i < c.size(); ++i) {
                nodes[i] = c[i].nodes;
                leaves[i] = c[i].leaves;
                tris[i] = c[i].tri_tests;
            }
            nlohmann::json j = base_record("ray_cost", s);
            j["structure"] = b.structure.name;
            j["kernel"] = trav::make_cpu_tracer(b.structure, o->build.kd_stack)->name();
            j["ray_type"] = trav::ray_type_name(t);
            j["rays"] = set.rays.size();
            j["nodes"] = distribution(std::move(nodes));
            j["leaves"] = distribution(std::move(leaves));
            j["tri_tests"] = distribution(std::move(tris));
            j["sah"] = b.stats.sah;
            j["epo"] = b.record["epo"];
            if (b.is_kd()) j["sah_constants"] = b.record["sah_constants"];
            j["protocol"] = protocol_json(o->rays.for_scene(s));
            if (g.json) {
                emit(j);
                continue;
            }
            auto cell = [](const nlohmann::json& d) {
                char buf[64];
                std::snprintf(buf, sizeof buf, "%.2f/%u/%u", d["mean"].get<double>(), d["p50"].get<uint32_t>(),
                              d["p99"].get<uint32_t>());
                return std::string(buf);
            };
            std::printf("%-10s %10zu   %-22s %-22s %-22s\n", trav::ray_type_name(t), set.rays.size(),
                        cell(j["nodes"]).c_str(), cell(j["leaves"]).c_str(), cell(j["tri_tests"]).c_str());
        }
    });
}

}  // namespace bvhlab::cli
