// SPDX-License-Identifier: MIT
// `bvhlab sweep`: a grid of bvhlab commands (scenes x option axes x repetitions) run as child
// processes, one worker per GPU and --jobs workers for CPU cells, each cell's JSON lines appended
// to a results file with the cell's key. A cell whose key is already in the results at this
// commit is skipped, so a killed sweep resumes where it stopped. docs/sweeps.md describes the
// spec file and the results.
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <utility>
#include <vector>

namespace bvhlab::cli::sweep {

/// The spec file: which command, over which scenes and option values, how often.
struct Spec {
    std::string path;     ///< the file it was read from
    std::string name;     ///< "name", or the file's stem
    std::string command;  ///< bench, verify, build, render or quality
    std::vector<std::string> scenes;
    /// The grid's axes in the file's order: an option name and its values (strings, numbers,
    /// or true/false for a flag that is given or not).
    std::vector<std::pair<std::string, std::vector<nlohmann::json>>> grid;
    std::vector<std::string> args;  ///< options every cell gets (the protocol)
    int repetitions = 1;
    std::string device;  ///< "cpu" or "gpu" for every cell, or "" to infer it from each cell's options
};

/// One run of the command.
struct Cell {
    size_t index = 0;  ///< position in the expanded grid (repetitions outermost)
    int rep = 0;
    std::string scene;
    std::vector<std::string> args;  ///< argv after the executable, ending in --json -q
    bool gpu = false;               ///< runs on a GPU worker
    std::string key;                ///< the cell's identity in the results (compact JSON)
    std::string label;              ///< "bench cornell-box --builder sbvh (rep 2)", for messages
};

/// Reads and checks a spec file (JSON); a bvhlab::Error names the file and the problem.
Spec read_spec(const std::string& path);

/// Every cell of the grid, repetitions outermost, then scenes, then the axes in the file's order.
/// "{cell}" and "{rep}" in option values become the cell's index and repetition.
std::vector<Cell> expand(const Spec& spec);

/// What the results on disk say: the keys done at `commit`, from `results` and its shard parts
/// (`results`.part-N).
struct Progress {
    std::vector<std::string> files;   ///< the files read
    std::vector<std::string> done;    ///< keys of cells with records at this commit (sorted, unique)
    size_t records = 0;               ///< JSON lines read
    size_t other_commit_records = 0;  ///< of those, lines from another commit
    size_t foreign_records = 0;       ///< lines that are not from a sweep cell
    bool has(const std::string& key) const;
};
Progress read_progress(const std::string& results, const std::string& commit);

/// The shard part files of `results` that exist.
std::vector<std::string> part_files(const std::string& results);

struct RunOptions {
    std::string exe;                ///< the bvhlab executable the cells run
    std::string results;            ///< appended to, one write per cell
    std::vector<std::string> gpus;  ///< CUDA_VISIBLE_DEVICES value of each GPU worker
    int jobs = 1;                   ///< CPU workers
    bool quiet = false;
};
struct RunSummary {
    size_t ran = 0, failed = 0;
    double seconds = 0.0;
};
/// Runs `cells` (already filtered to those not done) and appends their records.
RunSummary run(const Spec& spec, const std::vector<Cell>& cells, const RunOptions& opts);

/// Folds the shard parts into `results` (cells already there at the same commit are not added
/// twice), replacing it atomically, then removes the parts. Returns the cells added.
size_t merge_parts(const std::string& results);

/// Runs a program (found on PATH when it has no '/') to its end; stdout captured, stderr's last
/// non-empty line kept. extra_env entries ("NAME=value") replace inherited ones.
struct ChildResult {
    int exit_code = -1;    ///< the exit status, or 128 + signal
    std::string out;       ///< everything it wrote on stdout
    std::string err_tail;  ///< its last non-empty stderr line
};
ChildResult run_child(const std::string& program, const std::vector<std::string>& args,
                      const std::vector<std::string>& extra_env = {});

}  // namespace bvhlab::cli::sweep
