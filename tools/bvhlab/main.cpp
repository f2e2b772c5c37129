// SPDX-License-Identifier: MIT
// bvhlab: build acceleration structures from OBJ files, benchmark traversal, verify every hit
// against Embree. This file only wires up the subcommands.
#include <cstdio>
#include <exception>
#include <string>

#include "accel/core/check.h"
#include "tools/bvhlab/commands.h"
#include "tools/bvhlab/host_memory.h"

namespace bvhlab::cli {
int g_exit_code = 0;
}

int main(int argc, char** argv) {
    using namespace bvhlab::cli;
    CLI::App app{"bvhlab: ray-tracing acceleration structure testbed (commit " + std::string(bvhlab::git_commit()) +
                 ")"};
    app.require_subcommand(1);
    set_command_line(argc, argv);
    Globals g;
    app.add_flag("--json", g.json, "print one JSON object per line on stdout");
    app.add_flag("-q,--quiet", g.quiet, "no progress on stderr");
    app.add_flag("--no-scene-cache", g.no_scene_cache,
                 "parse scene files, neither reading nor writing the scene cache ($BVHLAB_CACHE_DIR)");
    app.add_flag("--flatten", g.flatten,
                 "make an instanced scene (a mesh placed more than once: glTF nodes, gen:instances) one mesh");
    app.set_version_flag("--version", std::string(bvhlab::git_commit()));
    register_build(app, g);
    register_rays(app, g);
    register_bench(app, g);
    register_verify(app, g);
    register_gen(app, g);
    register_run(app, g);
    register_quality(app, g);
    register_kernels(app, g);
    register_cache(app, g);
    register_render(app, g);
    register_sweep(app, g);
    register_rerun(app, g);
    register_report(app, g);
    // Global flags are also accepted after the subcommand name.
    for (CLI::App* sub : app.get_subcommands({})) {
        sub->add_flag("--json", g.json, "print one JSON object per line on stdout");
        sub->add_flag("-q,--quiet", g.quiet, "no progress on stderr");
        if (sub->get_name() != "cache" && sub->get_name() != "kernels" && sub->get_name() != "gen" &&
            sub->get_name() != "sweep" && sub->get_name() != "rerun" && sub->get_name() != "report") {
            sub->add_flag("--no-scene-cache", g.no_scene_cache, "parse scene files, bypassing the scene cache");
            sub->add_flag("--flatten", g.flatten, "make an instanced scene one mesh");
        }
    }
    // An unknown first word is named (CLI11 would only say that a subcommand is required).
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--json" || a == "-q" || a == "--quiet" || a == "--no-scene-cache" || a == "--flatten") continue;
        if (a.empty() || a[0] == '-') break;
        std::string known;
        std::vector<std::string> names;
        bool found = false;
        for (CLI::App* sub : app.get_subcommands({})) {
            known += (known.empty() ? "" : ", ") + sub->get_name();
            names.push_back(sub->get_name());
            found = found || sub->get_name() == a;
        }
        if (!found) {
            std::fprintf(stderr, "bvhlab: error: unknown command '%s'%s (commands: %s)\n", a.c_str(),
                         did_you_mean(a, names).c_str(), known.c_str());
            return 2;
        }
        break;
    }
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        std::fprintf(stderr, "bvhlab: error: %s (see --help)\n", e.what());
        return 2;
    } catch (const bvhlab::Error& e) {
        std::fprintf(stderr, "bvhlab: error: %s\n", e.what());
        return 1;
    } catch (const OutOfHostMemory& e) {
        std::fprintf(stderr, "bvhlab: error: out of host memory: an allocation of %s failed%s\n",
                     describe_bytes(e.bytes()).c_str(), failed_stage_clause().c_str());
        return 1;
    } catch (const std::bad_alloc&) {
        std::fprintf(stderr, "bvhlab: error: out of host memory%s\n", failed_stage_clause().c_str());
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bvhlab: error: %s\n", e.what());
        return 1;
    }
    return g_exit_code;
}
