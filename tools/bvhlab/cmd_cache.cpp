// SPDX-License-Identifier: MIT
// `bvhlab cache info|clear`: the scene cache's entries, or emptying it.
#include <cstdio>

#include "accel/core/check.h"
#include "scene/io/scene_cache.h"
#include "tools/bvhlab/commands.h"

namespace bvhlab::cli {

void register_cache(CLI::App& app, Globals& g) {
    auto action = std::make_shared<std::string>();
    CLI::App* sub = app.add_subcommand(
        "cache",
        "show (info) or empty (clear) the scene cache: $BVHLAB_CACHE_DIR, else $XDG_CACHE_HOME/bvhlab or "
        "~/.cache/bvhlab");
    sub->add_option("action", *action, "info or clear")->required()->check(CLI::IsMember({"info", "clear"}));
    sub->callback([&g, action] {
        const std::string dir = scene::default_scene_cache_dir();
        if (dir.empty()) throw Error("no scene cache folder: set BVHLAB_CACHE_DIR (or HOME)");
        if (*action == "clear") {
            uint64_t bytes = 0;
            const size_t n = scene::clear_scene_cache(dir, &bytes);
            if (g.json)
                emit({{"record", "scene_cache_clear"}, {"dir", dir}, {"removed", n}, {"bytes", bytes}});
            else
                std::printf("removed %zu files (%.1f MB) from %s\n", n, double(bytes) / 1e6, dir.c_str());
            return;
        }
        const auto entries = scene::list_scene_cache(dir);
        uint64_t total = 0;
        for (const auto& e : entries) {
            total += e.bytes;
            if (g.json) {
                emit({{"record", "scene_cache_entry"},
                      {"file", e.file},
                      {"bytes", e.bytes},
                      {"source", e.source},
                      {"triangles", e.triangles},
                      {"writer", e.writer},
                      {"usable", e.problem.empty()},
                      {"problem", e.problem}});
            } else if (e.problem.empty()) {
                std::printf("%-60s %10.1f MB  %10llu triangles  from %s (written by %s)\n", e.file.c_str(),
                            double(e.bytes) / 1e6, (unsigned long long)e.triangles, e.source.c_str(), e.writer.c_str());
            } else {
                std::printf("%-60s %10.1f MB  unusable: %s\n", e.file.c_str(), double(e.bytes) / 1e6,
                            e.problem.c_str());
            }
        }
        if (g.json)
            emit({{"record", "scene_cache"}, {"dir", dir}, {"entries", entries.size()}, {"bytes", total}});
        else
            std::printf("scene cache %s: %zu entries, %.1f MB\n", dir.c_str(), entries.size(), double(total) / 1e6);
    });
}

}  // namespace bvhlab::cli
