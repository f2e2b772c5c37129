// SPDX-License-Identifier: MIT
// `bvhlab verify`: every hit against Embree, ray by ray, for one tracer, every GPU kernel
// (--kernel all), or every structure with its tracers (--structure all); exit 1 on any real
// mismatch.
#include <cstdio>
#include <memory>

#include "accel/core/check.h"
#include "tools/bvhlab/commands.h"
#include "tools/bvhlab/pipeline.h"
#include "traversal/rays/ray_file.h"

namespace bvhlab::cli {

void print_verify_header() {
    std::printf("%-10s %-22s %-24s %12s %12s %8s %10s   %s\n", "rays", "structure", "kernel", "count", "agree", "ties",
                "mismatches", "ties: shared-edge/near-edge/interval-end/coincident");
}

void print_verify_row(const nlohmann::json& j) {
    const nlohmann::json& st = j.contains("structure") ? j["structure"] : nlohmann::json();
    const std::string structure = st.is_string() ? st.get<std::string>() : "";
    std::printf("%-10s %-22s %-24s %12zu %12zu %8zu %10zu   %zu/%zu/%zu/%zu", j["ray_type"].get<std::string>().c_str(),
                structure.c_str(), j["kernel"].get<std::string>().c_str(), j["rays"].get<size_t>(),
                j["agree"].get<size_t>(), j["ties"].get<size_t>(), j["mismatches"].get<size_t>(),
                j["ties_shared_edge"].get<size_t>(), j["ties_near_edge"].get<size_t>(),
                j["ties_interval_end"].get<size_t>(), j["ties_coincident"].get<size_t>());
    // Mismatches by kind (check_claimed_hit's and the disagreements'), when there are any.
    if (j.contains("mismatch_kinds"))
        for (const auto& [kind, n] : j["mismatch_kinds"].items())
            if (n.get<size_t>() > 0) std::printf("  %s %zu", kind.c_str(), n.get<size_t>());
    std::printf("\n");
}

namespace {

/// What --structure all checks: each BVH builder in both layouts, then the kd-tree with its
/// full stack and with the short stack of --kd-stack (2 unless given). An instanced scene's
/// structures are two-level: each BVH builder's BLAS in both layouts.
struct StructureSpec {
    std::string structure, layout;
    int kd_stack;
};
std::vector<StructureSpec> every_structure(int short_stack, bool instanced) {
    std::vector<StructureSpec> out;
    for (const char* b : {"binned", "sweep", "sbvh"})
        for (const char* layout : {"bvh2", "cwbvh"}) out.push_back({b, layout, 64});
    if (instanced) return out;
    out.push_back({"kdtree", "bvh2", 64});
    out.push_back({"kdtree", "bvh2", short_stack});
    return out;
}

}  // namespace

void register_verify(CLI::App& app, Globals& g) {
    struct Opts {
        std::string scene, types = "all", rays_file, hits_file;
        BuildOptions build;
        RayOptions rays;
        TraceOptions trace;
        trav::CompareConfig cc;
    };
    auto o = std::make_shared<Opts>();
    CLI::App* sub = app.add_subcommand("verify", "compare every hit with Embree; exit 1 on any real mismatch");
    sub->add_option("scene", o->scene, kSceneHelp)->required();
    auto* types = sub->add_option("--types", o->types, "comma-separated ray types, or all")->capture_default_str();
    auto* file = sub->add_option("--rays", o->rays_file, "verify on this ray file instead of protocol rays")
                     ->check(CLI::ExistingFile);
    file->excludes(types);
    auto* hits = sub->add_option("--hits", o->hits_file,
                                 "check this hit file (e.g. from another tool) instead of bvhlab's tracer")
                     ->check(CLI::ExistingFile)
                     ->needs(file);
    o->build.accepts_all = true;
    o->build.add_to(*sub);
    o->rays.add_to(*sub);
    o->rays.excluded_by(file);  // a ray file's rays are fixed: no protocol option applies
    add_compare_options(*sub, o->cc);
    o->trace.add_to(*sub, true);
    sub->get_option("--device")
        ->description("cpu (TBB over the shared traversal) or gpu (a CUDA kernel, see --kernel)");
    sub->callback([o, &g, file, hits] {
        if (o->trace.device == "embree")
            throw Error(
                "verify checks a tracer against Embree; --device embree would check Embree against itself "
                "(give --device cpu or gpu)");
        if (o->rays_file.empty()) o->rays.check_types(parse_ray_types(o->types), o->types);
        if (o->build.structure == "all") {
            // Every structure: options that choose one are refused, not silently ignored.
            std::vector<const CLI::Option*> one{o->build.builder_flag, o->build.layout_flag, o->build.collapse_flag,
                                                o->build.cw_tris_flag};
            one.insert(one.end(), o->build.config_flags.begin(), o->build.config_flags.end());
            one.insert(one.end(), o->build.kd_flags.begin(), o->build.kd_flags.end());
            for (const CLI::Option* f : one)
                if (f->count())
                    throw Error(f->get_name() +
                                " sets up one structure; --structure all checks every structure with its defaults");
            if (o->trace.kernel_flag->count() && o->trace.kernel != "all")
                throw Error("--kernel " + o->trace.kernel +
                            " traces one layout; --structure all checks every structure (use --kernel all)");
            if (hits->count()) throw Error("--hits checks a hit file; --structure all builds structures to check");
        }
        o->trace.validate(o->build);
        if (hits->count() && (o->trace.kernel_flag->count() || o->trace.device != "cpu"))
            throw Error("--hits checks a hit file; --device and --kernel choose a tracer, which it does not use");
        Scene s = load_scene(o->scene, g);
        const std::unique_ptr<trav::EmbreeOracle> oracle_owner = make_oracle(s);
        const trav::EmbreeOracle& oracle = *oracle_owner;
        std::vector<nlohmann::json> rows;
        auto check_one = [&](const CheckedSet& cs, const std::vector<trav::Hit>& ours, nlohmann::json fields) {
            Stage st(g, "verifying " + std::to_string(cs.set.rays.size()) + " " + cs.ray_type + " rays (" +
                            fields["kernel"].get<std::string>() + ") against Embree");
            nlohmann::json j = verify_hits(s, oracle, cs, ours, o->cc);
            j.update(fields);
            rows.push_back(std::move(j));
        };
        if (hits->count()) {
            const trav::RaySet set = read_rays_for(o->rays_file, "verify");
            trav::HitSet hs = trav::read_hit_file(o->hits_file);
            trav::check_hit_ids(hs, s.first_ids, o->hits_file);
            if (hs.hits.size() != set.rays.size())
                throw Error("hit file has " + std::to_string(hs.hits.size()) + " hits for " +
                            std::to_string(set.rays.size()) + " rays");
            if (hs.query != set.query) throw Error("hit file and ray file disagree on the query (closest vs any)");
            check_one(check_set(oracle, set, "file"), hs.hits,
                      {{"device", "file"}, {"structure", "hit-file"}, {"layout", nullptr}, {"kernel", "hit-file"}});
        } else {
            o->build.epo = false;
            // One structure, or with --structure all each of every_structure() in turn.
            std::vector<BuildOptions> builds;
            if (o->build.structure == "all") {
                const int short_stack =
                    o->build.kd_stack_flag->count() && o->build.kd_stack != trav::kKdFullStack ? o->build.kd_stack : 2;
                for (const StructureSpec& spec : every_structure(short_stack, s.placed != nullptr)) {
                    BuildOptions b = o->build;
                    b.structure = spec.structure;
                    b.builder = spec.structure == "kdtree" ? b.builder : spec.structure;
                    b.layout = spec.layout;
                    b.kd_stack = spec.kd_stack;
                    builds.push_back(std::move(b));
                }
            } else {
                builds.push_back(o->build);
            }
            // The ray sets (and Embree's answers) are made once and shared by every structure.
            std::vector<std::pair<trav::RaySet, std::string>> sets;
            if (file->count()) {
                sets.emplace_back(read_rays_for(o->rays_file, "verify"), "file");
            } else {
                trav::RayProtocol proto(s.mesh, oracle, o->rays.for_scene(s));
                for (trav::RayType t : parse_ray_types(o->types))
                    sets.emplace_back(proto.make(t), trav::ray_type_name(t));
            }
            std::vector<CheckedSet> checked;
            for (const auto& [set, type] : sets) checked.push_back(check_set(oracle, set, type));
            const nlohmann::json protocol = file->count() ? nlohmann::json() : protocol_json(o->rays.for_scene(s));
            for (BuildOptions& bo : builds) {
                Built b = build_scene(s, bo, g);
                auto tracers = make_tracers(b, o->trace, bo, nullptr);
                for (const CheckedSet& cs : checked) {
                    for (auto& t : tracers) {
                        std::vector<trav::Hit> ours;
                        t->trace(cs.set, ours);
                        check_one(cs, ours, tracer_fields(b, *t));
                        if (!file->count()) {
                            rows.back()["protocol"] = protocol;
                        } else {
                            rows.back()["ray_file"] = o->rays_file;
                            rows.back()["ray_file_hash"] = file_hash(o->rays_file);
                        }
                    }
                }
            }
        }
        if (!g.json) print_verify_header();
        for (const auto& j : rows) {
            if (g.json)
                emit(j);
            else
                print_verify_row(j);
            if (j["mismatches"].get<size_t>() > 0) g_exit_code = 1;
        }
        if (g_exit_code) std::fprintf(stderr, "bvhlab: error: real mismatches against Embree (see above)\n");
    });
}

}  // namespace bvhlab::cli
