// SPDX-License-Identifier: MIT
// `bvhlab rerun RECORD|FILE`: repeats the command lines that JSON records name ("argv", "cwd")
// and prints old and new figures side by side. A record from another commit is refused unless
// --force, and so is a comparison whose scene hash or ray file changed.
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>

#include "accel/core/check.h"
#include "tools/bvhlab/commands.h"
#include "tools/bvhlab/sweep.h"

namespace bvhlab::cli {

namespace fs = std::filesystem;

namespace {

/// The figures compared, in this order, where both records have them.
const char* const kFigures[] = {"mrays_per_s", "median_ms", "build_ms", "sah",        "epo",
                                "nodes",       "leaves",    "depth",    "mismatches", "ties"};

/// Options whose value is a file the command writes: a rerun writes them into a scratch folder.
bool writes_file(const std::string& option) {
    return option == "-o" || option == "--out" || option == "--hits-out" || option == "--cost-image";
}

/// What tells two records of one command line apart: the record kind, ray type, kernel, device, structure.
std::string signature(const nlohmann::json& j) {
    std::string s;
    for (const char* k : {"record", "ray_type", "structure", "device", "kernel", "layout"}) {
        const auto it = j.find(k);
        if (it != j.end() && it->is_string()) s += (s.empty() ? "" : " ") + it->get<std::string>();
    }
    return s;
}

std::string number_text(const nlohmann::json& v) {
    char buf[64];
    const double d = v.get<double>();
    if (v.is_number_integer() || v.is_number_unsigned())
        std::snprintf(buf, sizeof buf, "%.0f", d);
    else
        std::snprintf(buf, sizeof buf, std::fabs(d) >= 100 ? "%.1f" : "%.4g", d);
    return buf;
}

struct Group {
    std::vector<std::string> argv;
    std::string cwd;
    std::vector<nlohmann::json> records;
};

std::vector<nlohmann::json> read_records(const std::string& source, int line) {
    std::vector<nlohmann::json> out;
    if (!source.empty() && source[0] == '{') {
        const nlohmann::json j = nlohmann::json::parse(source, nullptr, false);
        if (j.is_discarded() || !j.is_object()) throw Error("the record given is not a JSON object");
        out.push_back(j);
    } else {
        if (!fs::exists(source)) throw Error("'" + source + "' does not exist (give a results file or a JSON record)");
        if (!fs::is_regular_file(source)) throw Error("'" + source + "' is not a regular file");
        std::ifstream in(source);
        int n = 0;
        for (std::string text; std::getline(in, text);) {
            ++n;
            if (text.find_first_not_of(" \t\r") == std::string::npos) continue;
            if (line && n != line) continue;
            const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
            if (j.is_discarded() || !j.is_object())
                throw Error("'" + source + "': line " + std::to_string(n) + " is not a JSON object");
            out.push_back(j);
        }
        if (line && out.empty())
            throw Error("'" + source + "' has no record on line " + std::to_string(line) + " (it has " +
                        std::to_string(n) + " lines)");
        if (out.empty()) throw Error("'" + source + "' holds no record");
    }
    return out;
}

}  // namespace

void register_rerun(CLI::App& app, Globals& g) {
    struct Options {
        std::string source;
        int line = 0;
        bool force = false;
    };
    auto o = std::make_shared<Options>();
    CLI::App* sub = app.add_subcommand(
        "rerun",
        "repeat the command line of JSON records (a results file, or one record) and show old and new figures");
    sub->add_option("RECORDS", o->source, "a file of JSON lines from bvhlab, or one JSON record as text")->required();
    sub->add_option("--line", o->line, "rerun only the record on this line of the file (1 = first)")
        ->check(CLI::Range(1, 1 << 30));
    sub->add_flag("--force", o->force,
                  "rerun records from another commit, and compare figures even when the scene or ray file changed");
    sub->callback([o, &g] {
        const std::vector<nlohmann::json> records = read_records(o->source, o->line);
        // One run per distinct command line; its records are matched to the old ones by kind.
        std::vector<Group> groups;
        size_t without_argv = 0;
        for (const nlohmann::json& r : records) {
            // A sweep's record names its cell's command line under "sweep" as well.
            static const nlohmann::json none;
            const nlohmann::json* line = r.contains("argv") ? &r["argv"] : &none;
            if (!line->is_array() && r.contains("sweep") && r["sweep"].is_object() && r["sweep"].contains("argv"))
                line = &r["sweep"]["argv"];
            if (!line->is_array() || line->empty()) {
                ++without_argv;
                continue;
            }
            std::vector<std::string> argv;
            for (const auto& a : *line)
                if (a.is_string()) argv.push_back(a.get<std::string>());
            const std::string cwd = r.value("cwd", std::string());
            auto it = std::find_if(groups.begin(), groups.end(),
                                   [&](const Group& gr) { return gr.argv == argv && gr.cwd == cwd; });
            if (it == groups.end()) {
                groups.push_back({argv, cwd, {}});
                it = groups.end() - 1;
            }
            it->records.push_back(r);
        }
        if (groups.empty())
            throw Error(std::string(records.size() == 1 ? "the record names no" : "no record names a") +
                        " command line (\"argv\"): it was written by a bvhlab older than the records that name "
                        "their command line, and cannot be rerun exactly");
        if (without_argv)
            std::fprintf(stderr,
                         "[bvhlab] warning: %zu of %zu records name no command line (older bvhlab) and are not rerun\n",
                         without_argv, records.size());
        for (const Group& gr : groups) {
            const std::string commit = gr.records.front().value("commit", std::string("unknown"));
            if (commit != git_commit() && !o->force)
                throw Error("a record comes from commit " + commit + " and this bvhlab is " + git_commit() +
                            ": its figures may differ for that reason alone (--force reruns it anyway)");
            if (gr.argv.front() == "rerun" || gr.argv.front() == "sweep")
                throw Error("a record of `bvhlab " + gr.argv.front() + "` is not rerun (rerun the records it wrote)");
        }

        const std::string exe = fs::read_symlink("/proc/self/exe").string();
        char scratch_template[] = "/tmp/bvhlab-rerun-XXXXXX";
        const char* scratch = mkdtemp(scratch_template);
        if (!scratch) throw Error("cannot make a scratch folder in /tmp");
        struct Cleanup {
            std::string dir;
            ~Cleanup() {
                std::error_code ec;
                fs::remove_all(dir, ec);
            }
        } cleanup{scratch};

        size_t refused = 0;
        if (!g.json) std::printf("%-56s %-12s %12s %12s %8s\n", "record", "figure", "old", "new", "change");
        for (const Group& gr : groups) {
            std::vector<std::string> args;
            for (size_t i = 0; i < gr.argv.size(); ++i) {
                const std::string& a = gr.argv[i];
                if (a == "--json" || a == "-q" || a == "--quiet") continue;
                args.push_back(a);
                if (writes_file(a) && i + 1 < gr.argv.size()) {
                    args.push_back(std::string(scratch) + "/" + std::to_string(i) + "-" +
                                   fs::path(gr.argv[i + 1]).filename().string());
                    ++i;
                }
            }
            args.push_back("--json");
            args.push_back("-q");
            std::string line;
            for (const std::string& a : gr.argv) line += " " + a;
            if (!g.quiet) std::fprintf(stderr, "[bvhlab] rerunning: bvhlab%s\n", line.c_str());
            // The old working folder, so that relative paths mean what they meant.
            const std::string here = fs::current_path().string();
            std::error_code ec;
            if (!gr.cwd.empty() && fs::is_directory(gr.cwd, ec)) fs::current_path(gr.cwd);
            const sweep::ChildResult r = sweep::run_child(exe, args);
            fs::current_path(here);
            if (r.exit_code != 0)
                throw Error("the rerun of `bvhlab" + line + "` failed (exit " + std::to_string(r.exit_code) + ")" +
                            (r.err_tail.empty() ? "" : ": " + r.err_tail));
            std::vector<nlohmann::json> fresh;
            std::stringstream ss(r.out);
            for (std::string l; std::getline(ss, l);)
                if (!l.empty()) fresh.push_back(nlohmann::json::parse(l, nullptr, false));
            std::vector<bool> used(fresh.size(), false);
            for (const nlohmann::json& old : gr.records) {
                size_t k = 0;
                while (k < fresh.size() && (used[k] || !fresh[k].is_object() || signature(fresh[k]) != signature(old)))
                    ++k;
                if (k == fresh.size()) {
                    std::fprintf(stderr, "[bvhlab] warning: the rerun printed no record matching '%s'\n",
                                 signature(old).c_str());
                    continue;
                }
                used[k] = true;
                const nlohmann::json& now = fresh[k];
                std::string why;
                for (const char* key : {"scene_hash", "ray_file_hash"})
                    if (old.contains(key) && now.contains(key) && old[key] != now[key])
                        why = std::string(key == std::string("scene_hash") ? "the scene" : "the ray file") +
                              " changed (" + key + " " + old[key].get<std::string>() + " then, " +
                              now[key].get<std::string>() + " now)";
                if (!why.empty() && !o->force) {
                    ++refused;
                    std::fprintf(stderr, "[bvhlab] %s: not compared: %s (--force compares anyway)\n",
                                 signature(old).c_str(), why.c_str());
                    continue;
                }
                nlohmann::json cmp = nlohmann::json::object();
                for (const char* f : kFigures) {
                    const auto a = old.find(f), b = now.find(f);
                    if (a == old.end() || b == now.end() || !a->is_number() || !b->is_number()) continue;
                    const double x = a->get<double>(), y = b->get<double>();
                    cmp[f] = {{"old", *a}, {"new", *b}, {"ratio", x != 0 ? nlohmann::json(y / x) : nlohmann::json()}};
                    if (!g.json) {
                        char change[32] = "";
                        if (x != 0) std::snprintf(change, sizeof change, "%+.1f%%", 100.0 * (y / x - 1.0));
                        std::string label = old.value("scene", "");
                        for (const char* k : {"ray_type", "structure", "device", "kernel"})
                            if (old.contains(k) && old[k].is_string()) label += " " + old[k].get<std::string>();
                        std::printf("%-56s %-12s %12s %12s %8s\n", label.c_str(), f, number_text(*a).c_str(),
                                    number_text(*b).c_str(), change);
                    }
                }
                if (g.json) {
                    nlohmann::json j = now;
                    j["rerun_of"] = {{"commit", old.value("commit", "")},
                                     {"figures", cmp},
                                     {"changed", why.empty() ? nlohmann::json() : nlohmann::json(why)}};
                    emit(j);
                }
            }
        }
        if (refused) throw Error(std::to_string(refused) + " records were not compared (reasons above)");
    });
}

}  // namespace bvhlab::cli
