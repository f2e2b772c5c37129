// SPDX-License-Identifier: MIT
// `bvhlab rays`: generate a protocol ray set and write it as a ray file, or describe one.
#include <cstdio>
#include <memory>

#include "accel/core/check.h"
#include "scene/io/atomic_file.h"
#include "tools/bvhlab/commands.h"
#include "traversal/oracle/embree_oracle.h"
#include "traversal/rays/ray_file.h"

namespace bvhlab::cli {

void register_rays(CLI::App& app, Globals& g) {
    struct Opts {
        std::string scene, type = "primary", out, info;
        RayOptions rays;
    };
    auto o = std::make_shared<Opts>();
    CLI::App* sub =
        app.add_subcommand("rays", "generate a seeded ray set and export it as a ray file, or describe a ray file");
    auto* scene = sub->add_option("scene", o->scene, kSceneHelp);
    // --types, as bench, verify and run name it (--type is kept for old scripts); one per file.
    auto* type =
        sub->add_option("--types,--type", o->type, "the ray type: primary, ao, diffuse or shadow (one per file)")
            ->capture_default_str();
    auto* out = sub->add_option("-o,--out", o->out, "ray file to write");
    auto* info =
        sub->add_option("--info", o->info, "print the header and ray count of a ray file")->check(CLI::ExistingFile);
    info->excludes(scene)->excludes(out)->excludes(type);
    o->rays.add_to(*sub);
    sub->callback([o, &g, scene, out, info] {
        if (info->count()) {
            trav::RaySet set = trav::read_ray_file(o->info);
            const std::string writer = set.writer.empty() ? "not recorded (version 1)" : set.writer;
            nlohmann::json j{{"record", "ray_file"},
                             {"file", o->info},
                             {"version", set.version},
                             {"writer", writer},
                             {"checksum", set.version >= 2 ? "ok" : "none (version 1)"},
                             {"query", set.query == trav::Query::kAny ? "any" : "closest"},
                             {"rays", set.rays.size()}};
            if (g.json)
                emit(j);
            else
                std::printf("%s: %zu rays, %s-hit, version %u, written by %s%s\n", o->info.c_str(), set.rays.size(),
                            set.query == trav::Query::kAny ? "any" : "closest", set.version, writer.c_str(),
                            set.version >= 2 ? ", checksum ok" : "");
            return;
        }
        if (!scene->count()) throw Error("rays needs a scene (or --info FILE)");
        if (o->type.find(',') != std::string::npos || o->type == "all")
            throw Error("--types " + o->type + ": a ray file holds one ray type; run rays once per type");
        if (o->type != "primary" && o->type != "ao" && o->type != "diffuse" && o->type != "shadow")
            throw Error("--types " + o->type + ": not a ray type (primary, ao, diffuse or shadow)" +
                        did_you_mean(o->type, {"primary", "ao", "diffuse", "shadow"}));
        if (!out->count()) throw Error("rays needs --out FILE for the ray set");
        const std::vector<scene::NamedFile> outputs{{"--out", o->out}};
        scene::refuse_clashing_files(outputs, {{"the scene", o->scene}});
        Scene s = load_scene(o->scene, g);
        scene::refuse_clashing_files(outputs, s.input_files());
        const std::unique_ptr<trav::EmbreeOracle> oracle_owner = make_oracle(s);
        const trav::EmbreeOracle& oracle = *oracle_owner;
        trav::RayProtocol proto(s.mesh, oracle, o->rays.for_scene(s));
        trav::RaySet set;
        {
            Stage st(g, "generating " + o->type + " rays");
            set = proto.make(trav::parse_ray_type(o->type));
        }
        set.writer = git_commit();
        trav::write_ray_file(o->out, set);
        nlohmann::json j = base_record("rays", s);
        j["ray_type"] = o->type;
        j["rays"] = set.rays.size();
        j["file"] = o->out;
        j["seed"] = o->rays.cfg.seed;
        if (g.json)
            emit(j);
        else
            std::printf("wrote %zu %s rays to %s\n", set.rays.size(), o->type.c_str(), o->out.c_str());
    });
}

}  // namespace bvhlab::cli
