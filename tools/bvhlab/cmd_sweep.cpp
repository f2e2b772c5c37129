// SPDX-License-Identifier: MIT
// `bvhlab sweep SPEC`: runs a grid of bvhlab commands over the GPUs and cores of this host, or
// submits it to Slurm as a job array; resumable; --status reports progress from the results.
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>

#include "accel/core/check.h"
#include "tools/bvhlab/commands.h"
#include "tools/bvhlab/sweep.h"
#include "traversal/gpu/device_buffer.h"

namespace bvhlab::cli {

namespace fs = std::filesystem;

namespace {

struct SweepOptions {
    std::string spec;
    std::string results;
    std::string gpus;
    std::string shard;
    int jobs = 1;
    bool dry_run = false;
    bool status = false;
    bool merge = false;
    bool slurm = false;
    int tasks = 0;
    int gpus_per_task = 1;
    std::vector<std::string> sbatch_args;
    CLI::Option* gpus_flag = nullptr;
    CLI::Option* jobs_flag = nullptr;
    CLI::Option* tasks_flag = nullptr;
    CLI::Option* gpt_flag = nullptr;
    CLI::Option* sbatch_flag = nullptr;
};

/// Every option of the grid and the fixed arguments exists on the command, and takes a value
/// exactly when the spec gives it one: a typo fails here, not in each of 200 cells.
void check_options(CLI::App& app, const sweep::Spec& spec) {
    CLI::App* cmd = app.get_subcommand(spec.command);
    std::vector<std::string> names;
    for (const CLI::Option* o : cmd->get_options())
        for (const std::string& l : o->get_lnames()) names.push_back("--" + l);
    const auto find = [&](const std::string& name, const std::string& where) {
        const CLI::Option* o = cmd->get_option_no_throw(name);
        if (!o)
            throw Error("sweep spec '" + spec.path + "': " + where + ": " + spec.command + " has no option " + name +
                        did_you_mean(name, names));
        return o;
    };
    for (const auto& [name, values] : spec.grid) {
        const CLI::Option* o = find(name, "grid axis '" + name + "'");
        const bool flag = o->get_expected_min() == 0;
        for (const nlohmann::json& v : values)
            if (v.is_boolean() != flag)
                throw Error("sweep spec '" + spec.path + "': grid axis '" + name + "': " +
                            (flag ? name + " is a flag: its values are true and false"
                                  : name + " takes a value, not " + v.dump()));
    }
    for (const std::string& a : spec.args)
        if (a.size() > 2 && a.rfind("--", 0) == 0) find(a.substr(0, a.find('=')), "\"args\"");
}

std::vector<std::string> visible_gpus(const SweepOptions& o) {
    std::vector<std::string> out;
    const auto split = [&](const std::string& list) {
        std::stringstream ss(list);
        for (std::string t; std::getline(ss, t, ',');)
            if (!t.empty()) out.push_back(t);
    };
    if (o.gpus_flag->count()) {
        split(o.gpus);
        if (out.empty()) throw Error("--gpus names no GPU (give a comma-separated list such as 0,1)");
        return out;
    }
    if (const char* v = std::getenv("CUDA_VISIBLE_DEVICES")) {
        split(v);
        // The runtime counts what it can use of these; the names are passed on as given.
        out.resize(std::min<size_t>(out.size(), size_t(trav::gpu_count())));
        return out;
    }
    for (int i = 0; i < trav::gpu_count(); ++i) out.push_back(std::to_string(i));
    return out;
}

std::pair<int, int> parse_shard(const std::string& s) {
    const size_t slash = s.find('/');
    char* end = nullptr;
    const long i = slash == std::string::npos ? -1 : std::strtol(s.c_str(), &end, 10);
    const bool i_ok = slash != std::string::npos && end == s.c_str() + slash && slash > 0;
    const long n = i_ok ? std::strtol(s.c_str() + slash + 1, &end, 10) : 0;
    if (!i_ok || *end != '\0' || slash + 1 == s.size() || n < 1 || n > 100000 || i < 0 || i >= n)
        throw Error("--shard " + s + ": expected I/N with 0 <= I < N (the task's number and the task count)");
    return {int(i), int(n)};
}

std::string absolute(const std::string& p) { return fs::absolute(p).lexically_normal().string(); }

std::string shell_quote(const std::string& s) {
    std::string out = "'";
    for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
}

void submit_slurm(const sweep::Spec& spec, const std::vector<sweep::Cell>& todo, const SweepOptions& o,
                  const std::string& results, const Globals& g) {
    const int tasks = o.tasks_flag->count() ? o.tasks : int(std::min<size_t>(todo.size(), 16));
    const bool gpu = std::any_of(todo.begin(), todo.end(), [](const sweep::Cell& c) { return c.gpu; });
    const std::string exe = fs::read_symlink("/proc/self/exe").string();
    const std::string res = absolute(results);
    const std::string script_path = res + ".slurm.sh";
    std::string script = "#!/bin/bash\n";
    script += "#SBATCH --job-name=bvhlab-" + spec.name + "\n";
    script += "#SBATCH --array=0-" + std::to_string(tasks - 1) + "\n";
    script += "#SBATCH --output=" + res + ".slurm-%A_%a.log\n";
    if (gpu) script += "#SBATCH --gres=gpu:" + std::to_string(o.gpus_per_task) + "\n";
    if (o.jobs > 1) script += "#SBATCH --cpus-per-task=" + std::to_string(o.jobs) + "\n";
    script += "# Written by bvhlab sweep --slurm: task I runs the cells whose index is I modulo " +
              std::to_string(tasks) + ",\n# appending to " + res + ".part-I.\n";
    script += "set -euo pipefail\ncd " + shell_quote(absolute(".")) + "\n";
    script += "exec " + shell_quote(exe) + " sweep " + shell_quote(absolute(spec.path)) + " --results " +
              shell_quote(res) + " --shard \"${SLURM_ARRAY_TASK_ID}/" + std::to_string(tasks) + "\" --jobs " +
              std::to_string(o.jobs) + "\n";
    scene::write_file_atomically(script_path, [&](std::FILE* f) { std::fputs(script.c_str(), f); });
    fs::permissions(script_path, fs::perms::owner_exec | fs::perms::group_exec, fs::perm_options::add);

    const char* sbatch_env = std::getenv("BVHLAB_SBATCH");
    const std::string sbatch = sbatch_env && *sbatch_env ? sbatch_env : "sbatch";
    const auto submit = [&](std::vector<std::string> args) {
        args.insert(args.begin(), "--parsable");
        for (const std::string& a : o.sbatch_args) args.insert(args.begin() + 1, a);
        sweep::ChildResult r;
        try {
            r = sweep::run_child(sbatch, args);
        } catch (const Error& e) {
            throw Error(std::string("cannot run sbatch: ") + e.what());
        }
        if (r.exit_code == 127)
            throw Error("cannot run '" + sbatch + "' (is Slurm installed? BVHLAB_SBATCH names another sbatch)");
        if (r.exit_code != 0)
            throw Error("sbatch refused the job (exit " + std::to_string(r.exit_code) + ")" +
                        (r.err_tail.empty() ? "" : ": " + r.err_tail));
        std::string id = r.out.substr(0, r.out.find_first_of(";\n"));
        if (id.empty()) throw Error("sbatch printed no job id");
        return id;
    };
    const std::string array_id = submit({script_path});
    const std::string merge_id =
        submit({"--dependency=afterany:" + array_id, "--job-name=bvhlab-" + spec.name + "-merge",
                "--output=" + res + ".slurm-merge-%j.log",
                "--wrap=" + shell_quote(exe) + " sweep " + shell_quote(absolute(spec.path)) + " --results " +
                    shell_quote(res) + " --merge"});
    if (g.json) {
        emit({{"record", "sweep_submit"},
              {"spec", spec.path},
              {"results", res},
              {"cells", todo.size()},
              {"tasks", tasks},
              {"array_job", array_id},
              {"merge_job", merge_id},
              {"script", script_path}});
    } else {
        std::printf(
            "sweep '%s': %zu cells submitted as Slurm array job %s (%d tasks), merge job %s; script %s\n"
            "progress: bvhlab sweep %s --results %s --status\n",
            spec.name.c_str(), todo.size(), array_id.c_str(), tasks, merge_id.c_str(), script_path.c_str(),
            spec.path.c_str(), results.c_str());
    }
}

}  // namespace

void register_sweep(CLI::App& app, Globals& g) {
    auto o = std::make_shared<SweepOptions>();
    CLI::App* sub = app.add_subcommand(
        "sweep",
        "run a grid of bench/verify/build/render/quality cells (a JSON spec: scenes x option axes x repetitions) over "
        "this host's GPUs and cores, or as a Slurm job array; resumable (docs/sweeps.md)");
    sub->add_option("SPEC", o->spec, "the sweep's spec file (JSON; docs/sweeps.md)")->required();
    sub->add_option("--results", o->results,
                    "the results file, JSON lines appended per cell (default: SPEC's name with .results.jsonl)");
    o->jobs_flag = sub->add_option("--jobs", o->jobs, "CPU cells run at once (default 1: a CPU cell uses every core)")
                       ->check(CLI::Range(1, 1024));
    o->gpus_flag = sub->add_option("--gpus", o->gpus,
                                   "GPUs to use, as CUDA_VISIBLE_DEVICES names them (default: every visible GPU), "
                                   "one worker each");
    sub->add_flag("--dry-run", o->dry_run, "list the cells, each marked done or to run, and run none");
    sub->add_flag("--status", o->status, "report progress from the results on disk and run nothing");
    sub->add_option("--shard", o->shard, "run only the cells whose index is I modulo N (I/N), into RESULTS.part-I");
    sub->add_flag("--merge", o->merge, "fold the shards' part files into the results file and remove them");
    sub->add_flag("--slurm", o->slurm,
                  "submit the cells still to run as a Slurm job array (sbatch --array) and a merge job after it");
    o->tasks_flag = sub->add_option("--tasks", o->tasks, "--slurm: array tasks (default: cells to run, at most 16)")
                        ->check(CLI::Range(1, 100000));
    o->gpt_flag = sub->add_option("--gpus-per-task", o->gpus_per_task,
                                  "--slurm: GPUs each task asks for when the grid has GPU cells (default 1)")
                      ->check(CLI::Range(1, 64));
    o->sbatch_flag = sub->add_option("--sbatch-arg", o->sbatch_args,
                                     "--slurm: an option passed to sbatch as is (repeatable), e.g. --partition=gpu");
    sub->callback([&app, &g, o] {
        const auto modes = int(o->status) + int(o->merge) + int(o->slurm) + int(o->dry_run);
        if (modes > 1) throw Error("--status, --merge, --slurm and --dry-run each do one thing: give one of them");
        if (!o->slurm)
            for (const CLI::Option* f : {o->tasks_flag, o->gpt_flag, o->sbatch_flag})
                if (f->count()) throw Error(f->get_name() + " applies to --slurm only");
        if (!o->shard.empty() && (o->slurm || o->merge || o->status))
            throw Error("--shard runs one task's cells; it does not combine with --slurm, --merge or --status");
        sweep::Spec spec = sweep::read_spec(o->spec);
        check_options(app, spec);
        const std::string results =
            o->results.empty()
                ? (fs::path(o->spec).parent_path() / fs::path(o->spec).stem()).string() + ".results.jsonl"
                : o->results;
        std::error_code ec;
        if (fs::exists(results) && fs::equivalent(results, o->spec, ec))
            throw Error("--results '" + results + "' is the spec file: the results would overwrite it");
        if (fs::is_directory(results)) throw Error("--results '" + results + "' is a folder");
        if (o->merge) {
            const size_t added = sweep::merge_parts(results);
            if (g.json)
                emit({{"record", "sweep_merge"}, {"results", results}, {"cells_added", added}});
            else
                std::printf("sweep '%s': %zu cells merged into %s\n", spec.name.c_str(), added, results.c_str());
            return;
        }
        const std::vector<sweep::Cell> cells = sweep::expand(spec);
        const sweep::Progress progress = sweep::read_progress(results, git_commit());
        std::vector<sweep::Cell> todo;
        for (const sweep::Cell& c : cells)
            if (!progress.has(c.key)) todo.push_back(c);
        const size_t gpu_todo = size_t(std::count_if(todo.begin(), todo.end(), [](const auto& c) { return c.gpu; }));
        if (o->status) {
            const size_t done = cells.size() - todo.size();
            if (g.json) {
                emit({{"record", "sweep_status"},
                      {"spec", spec.path},
                      {"results", results},
                      {"files", progress.files},
                      {"cells", cells.size()},
                      {"done", done},
                      {"to_run", todo.size()},
                      {"to_run_gpu", gpu_todo},
                      {"records_other_commits", progress.other_commit_records}});
            } else {
                std::printf("sweep '%s': %zu of %zu cells done at commit %s (%.0f%%), %zu to run (%zu GPU, %zu CPU)\n",
                            spec.name.c_str(), done, cells.size(), git_commit(),
                            cells.empty() ? 100.0 : 100.0 * double(done) / double(cells.size()), todo.size(), gpu_todo,
                            todo.size() - gpu_todo);
                std::printf("results: %s%s\n", results.c_str(),
                            progress.files.size() > 1
                                ? (" and " + std::to_string(progress.files.size() - (fs::exists(results) ? 1 : 0)) +
                                   " part files (bvhlab sweep --merge folds them in)")
                                      .c_str()
                                : "");
                if (progress.other_commit_records)
                    std::printf("%zu records from other commits are kept and not counted\n",
                                progress.other_commit_records);
            }
            return;
        }
        if (o->dry_run) {
            for (const sweep::Cell& c : cells) {
                std::string line;
                for (const std::string& a : c.args) line += " " + a;
                if (g.json)
                    emit({{"record", "sweep_cell"},
                          {"cell", c.index},
                          {"gpu", c.gpu},
                          {"done", progress.has(c.key)},
                          {"argv", c.args},
                          {"key", c.key}});
                else
                    std::printf("cell %zu %s %s: bvhlab%s\n", c.index, c.gpu ? "gpu" : "cpu",
                                progress.has(c.key) ? "done" : "to run", line.c_str());
            }
            return;
        }
        if (o->slurm) {
            if (todo.empty()) {
                std::printf("sweep '%s': every cell is done; nothing to submit\n", spec.name.c_str());
                return;
            }
            submit_slurm(spec, todo, *o, results, g);
            return;
        }
        std::vector<sweep::Cell> mine;
        std::string out = results;
        if (!o->shard.empty()) {
            const auto [i, n] = parse_shard(o->shard);
            for (const sweep::Cell& c : todo)
                if (c.index % size_t(n) == size_t(i)) mine.push_back(c);
            out = results + ".part-" + std::to_string(i);
        } else {
            mine = todo;
        }
        sweep::RunOptions ro;
        ro.exe = fs::read_symlink("/proc/self/exe").string();
        ro.results = out;
        ro.jobs = o->jobs;
        ro.quiet = g.quiet;
        const size_t gpu_mine = size_t(std::count_if(mine.begin(), mine.end(), [](const auto& c) { return c.gpu; }));
        if (gpu_mine) {
            ro.gpus = visible_gpus(*o);
            if (ro.gpus.empty())
                throw Error("the sweep has " + std::to_string(gpu_mine) +
                            " GPU cells left and this machine has no GPU (a cell is a GPU cell when it says --device "
                            "gpu, --build-device gpu or a GPU builder, or the spec says \"device\": \"gpu\")");
        }
        if (!g.quiet)
            std::fprintf(
                stderr, "[bvhlab] sweep '%s': %zu cells, %zu done, %zu to run here (%s)\n", spec.name.c_str(),
                cells.size(), cells.size() - todo.size(), mine.size(),
                ro.gpus.empty()
                    ? ("CPU workers: " + std::to_string(o->jobs)).c_str()
                    : (std::to_string(ro.gpus.size()) + " GPU workers, " + std::to_string(o->jobs) + " CPU").c_str());
        const sweep::RunSummary sum = sweep::run(spec, mine, ro);
        if (g.json) {
            emit({{"record", "sweep"},
                  {"spec", spec.path},
                  {"results", out},
                  {"cells", cells.size()},
                  {"skipped_done", cells.size() - todo.size()},
                  {"ran", sum.ran},
                  {"failed", sum.failed},
                  {"seconds", sum.seconds},
                  {"gpus", ro.gpus},
                  {"jobs", o->jobs}});
        } else {
            std::printf("sweep '%s': %zu cells ran, %zu failed, %zu already done; %.1f s; results in %s\n",
                        spec.name.c_str(), sum.ran, sum.failed, cells.size() - todo.size(), sum.seconds, out.c_str());
        }
        if (sum.failed)
            throw Error(std::to_string(sum.failed) + " of " + std::to_string(mine.size()) +
                        " cells failed (their errors are above); run the sweep again to retry them");
    });
}

}  // namespace bvhlab::cli
