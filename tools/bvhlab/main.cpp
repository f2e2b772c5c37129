// SPDX-License-Identifier: MIT
// bvhlab: build acceleration structures from OBJ files, benchmark traversal, verify every hit
// against Embree. This file only wires up the subcommands.
#include <cstdio>
#include <exception>
#include <string>
#include <utility>
#include <vector>

#include "accel/core/check.h"
#include "tools/bvhlab/commands.h"
#include "tools/bvhlab/host_memory.h"

namespace bvhlab::cli {
int g_exit_code = 0;
}

namespace {

/// The help heading of a command's option, by its name; null keeps CLI11's "Options".
const char* help_group(const std::string& name, const std::string& command) {
    static const std::vector<std::pair<const char*, std::vector<std::string>>> groups{
        {"Structure",
         {"--structure",   "--builder",  "--build-device", "--layout",       "--max-leaf",      "--min-leaf",
          "--bins",        "--alpha",    "--budget",       "--spatial-bins", "--reinsert",      "--collapse",
          "--cw-tris",     "--kd-bonus", "--kd-ci",        "--kd-ct",        "--kd-max-depth",  "--kd-stack",
          "--morton-bits", "--radius",   "--no-epo",       "--flatten",      "--no-scene-cache"}},
        {"Rays",
         {"--types", "--rays", "--width", "--height", "--spp", "--tile", "--seed", "--diffuse-rays", "--ao-rays",
          "--eye", "--target", "--up", "--fov", "--camera", "--fisheye-fov"}},
        {"Device and timing", {"--device", "--kernel", "--block-size", "--fetch-threshold", "--runs", "--warmup"}},
        {"Verification", {"--edge-eps", "--t-tol", "--hits"}},
        {"Output", {"--json", "--quiet", "--out", "--hits-out", "--cost-image", "--aov", "--dump-rays", "--info"}},
    };
    if (command == "render" && (name == "--seed" || name == "--spp" || name == "--width" || name == "--height"))
        return "Image and sampling";
    for (const auto& [heading, names] : groups)
        for (const std::string& n : names)
            if (name == n) return heading;  // get_name() is the first long name: "--out" for "-o,--out"
    return nullptr;
}

}  // namespace

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
    // Help text in groups: each option under the heading of what it chooses; examples below.
    static const std::vector<std::pair<std::string, std::string>> examples{
        {"build",
         "  bvhlab build stanford-bunny --builder sbvh --max-leaf 4\n"
         "  bvhlab build furball --builder hploc --runs 10 --json     # a GPU build, timed\n"
         "  bvhlab build sibenik --layout cwbvh -o sibenik.bvh        # saved for --structure sibenik.bvh"},
        {"rays", "  bvhlab rays stanford-bunny --types diffuse -o diffuse.rays\n  bvhlab rays --info diffuse.rays"},
        {"bench",
         "  bvhlab bench stanford-bunny --device gpu --kernel all --types primary,diffuse\n"
         "  bvhlab bench furball --device gpu --builder sbvh --rays diffuse.rays\n"
         "  bvhlab bench dragon-100k --device embree"},
        {"verify",
         "  bvhlab verify sibenik --structure all --device gpu --kernel all\n"
         "  bvhlab verify stanford-bunny --rays diffuse.rays --hits my-tracer.hits   # another tracer's hits"},
        {"run",
         "  bvhlab run                         # the Cornell box, and $BVHLAB_SCENES' scenes\n"
         "  bvhlab run stanford-bunny --device gpu --no-epo"},
        {"quality", "  bvhlab quality furball --structure sbvh --types primary,diffuse"},
        {"render",
         "  bvhlab render cornell-box --device gpu --spp 256 -o cornell.png --aov\n"
         "  bvhlab render sibenik --device gpu --time-limit 10 --env sky.exr -o sibenik.exr"},
        {"sweep",
         "  bvhlab sweep grid.json              # results in grid.results.jsonl\n"
         "  bvhlab sweep grid.json --status\n"
         "  bvhlab sweep grid.json --slurm --tasks 8 --sbatch-arg=--partition=gpu"},
        {"rerun", "  bvhlab rerun grid.results.jsonl --line 12"},
    };
    for (CLI::App* sub : app.get_subcommands({}))
        for (const auto& [name, text] : examples)
            if (sub->get_name() == name) sub->footer("\nExamples:\n" + text);
    for (CLI::App* sub : app.get_subcommands({}))
        for (CLI::Option* opt : sub->get_options())
            if (const char* heading = help_group(opt->get_name(), sub->get_name())) opt->group(heading);
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
