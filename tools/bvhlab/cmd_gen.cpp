// SPDX-License-Identifier: MIT
// `bvhlab gen`: write a seeded procedural scene (random soup or structured) as OBJ.
#include <cstdio>
#include <memory>

#include "scene/io/obj_loader.h"
#include "scene/io/procedural.h"
#include "tools/bvhlab/commands.h"

namespace bvhlab::cli {

void register_gen(CLI::App& app, Globals& g) {
    struct Opts {
        std::string kind = "soup", out;
        uint64_t triangles = 100000, seed = 1;
    };
    auto o = std::make_shared<Opts>();
    CLI::App* sub = app.add_subcommand("gen", "write a procedural scene with exactly N triangles as OBJ");
    sub->add_option("--kind", o->kind, "soup (random triangles) or structured (height field and boxes)")
        ->check(CLI::IsMember({"soup", "structured"}))
        ->capture_default_str();
    sub->add_option("-n,--triangles", o->triangles, "number of triangles")
        ->check(CLI::Range(uint64_t(1), uint64_t(1) << 30))
        ->capture_default_str();
    sub->add_option("--seed", o->seed, "random seed")->check(UInt64())->capture_default_str();
    sub->add_option("-o,--out", o->out, "OBJ file to write")->required();
    sub->callback([o, &g] {
        scene::TriangleMesh m;
        {
            Stage st(g, "generating " + std::to_string(o->triangles) + " " + o->kind + " triangles");
            m = scene::make_procedural(scene::parse_procedural_kind(o->kind), o->triangles, o->seed);
        }
        {
            Stage st(g, "writing " + o->out);
            scene::write_obj(m, o->out);
        }
        nlohmann::json j{{"record", "gen"}, {"kind", o->kind}, {"triangles", m.triangle_count()},
                         {"seed", o->seed}, {"file", o->out},  {"scene_hash", scene::scene_hash(m)}};
        if (g.json)
            emit(j);
        else
            std::printf("wrote %zu %s triangles to %s\n", m.triangle_count(), o->kind.c_str(), o->out.c_str());
    });
}

}  // namespace bvhlab::cli
