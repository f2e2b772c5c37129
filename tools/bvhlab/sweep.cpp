// SPDX-License-Identifier: MIT
#include "tools/bvhlab/sweep.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <thread>

#include "accel/core/check.h"
#include "scene/io/atomic_file.h"

extern char** environ;

namespace bvhlab::cli::sweep {

namespace fs = std::filesystem;

namespace {

[[noreturn]] void bad_spec(const std::string& path, const std::string& why) {
    throw Error("sweep spec '" + path + "': " + why);
}

/// An option value as the command line writes it.
std::string value_text(const nlohmann::json& v) { return v.is_string() ? v.get<std::string>() : v.dump(); }

std::string substitute(std::string s, size_t cell, int rep) {
    for (const auto& [from, to] : {std::pair<std::string, std::string>{"{cell}", std::to_string(cell)},
                                   std::pair<std::string, std::string>{"{rep}", std::to_string(rep)}})
        for (size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size()))
            s.replace(at, from.size(), to);
    return s;
}

/// Whether a cell runs on a GPU: its --device or --build-device says gpu, or its builder is one
/// of the GPU builders (which run nowhere else).
bool needs_gpu(const std::vector<std::string>& args) {
    for (size_t i = 0; i + 1 < args.size(); ++i) {
        const std::string& a = args[i];
        const std::string& v = args[i + 1];
        if ((a == "--device" || a == "--build-device") && v == "gpu") return true;
        if (a == "--builder" && (v == "lbvh" || v == "ploc" || v == "hploc" || v == "gpu-binned")) return true;
    }
    return false;
}

std::string format_duration(double s) {
    char buf[32];
    if (s < 60)
        std::snprintf(buf, sizeof buf, "%.0fs", s);
    else if (s < 3600)
        std::snprintf(buf, sizeof buf, "%dm%02ds", int(s) / 60, int(s) % 60);
    else
        std::snprintf(buf, sizeof buf, "%dh%02dm", int(s) / 3600, (int(s) % 3600) / 60);
    return buf;
}

void write_all(int fd, const std::string& text, const std::string& path) {
    size_t done = 0;
    while (done < text.size()) {
        const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) throw Error("cannot write the results file '" + path + "': " + std::strerror(errno));
        done += size_t(n);
    }
}

}  // namespace

Spec read_spec(const std::string& path) {
    std::ifstream in(path);
    if (!in) bad_spec(path, fs::exists(path) ? "cannot be read" : "does not exist");
    if (fs::is_directory(path)) bad_spec(path, "is a folder");
    // Ordered, so that the cells come in the order the file lists the axes.
    const nlohmann::ordered_json j = nlohmann::ordered_json::parse(in, nullptr, /*allow_exceptions=*/false);
    if (j.is_discarded()) bad_spec(path, "is not valid JSON");
    if (!j.is_object()) bad_spec(path, "must hold one JSON object");
    static const std::vector<std::string> keys{"name", "command", "scenes", "grid", "args", "repetitions", "device"};
    for (const auto& [k, v] : j.items())
        if (std::find(keys.begin(), keys.end(), k) == keys.end())
            bad_spec(path, "unknown key '" + k + "' (keys: name, command, scenes, grid, args, repetitions, device)");
    Spec s;
    s.path = path;
    s.name = j.value("name", fs::path(path).stem().string());
    if (!j.contains("command") || !j["command"].is_string()) bad_spec(path, "needs \"command\": a bvhlab command");
    s.command = j["command"].get<std::string>();
    static const std::vector<std::string> commands{"bench", "verify", "build", "render", "quality"};
    if (std::find(commands.begin(), commands.end(), s.command) == commands.end())
        bad_spec(path,
                 "command '" + s.command + "' cannot be swept (it takes bench, verify, build, render or quality)");
    const auto strings = [&](const char* key, bool required) {
        std::vector<std::string> out;
        if (!j.contains(key)) {
            if (required) bad_spec(path, std::string("needs \"") + key + "\": a list of strings");
            return out;
        }
        if (!j[key].is_array()) bad_spec(path, std::string("\"") + key + "\" must be a list of strings");
        for (const auto& e : j[key]) {
            if (!e.is_string() && !e.is_number())
                bad_spec(path, std::string("\"") + key + "\" holds " + e.dump() + ", not a string");
            out.push_back(value_text(e));
        }
        return out;
    };
    s.scenes = strings("scenes", true);
    if (s.scenes.empty()) bad_spec(path, "\"scenes\" is empty");
    s.args = strings("args", false);
    if (j.contains("grid")) {
        if (!j["grid"].is_object()) bad_spec(path, "\"grid\" must be an object of option names and lists of values");
        for (const auto& [name, values] : j["grid"].items()) {
            if (name.rfind("-", 0) != 0)
                bad_spec(path, "grid axis '" + name + "' is not an option (options start with -)");
            if (!values.is_array() || values.empty())
                bad_spec(path, "grid axis '" + name + "' needs a non-empty list of values");
            std::vector<nlohmann::json> vs;
            for (const auto& v : values) {
                if (!v.is_string() && !v.is_number() && !v.is_boolean())
                    bad_spec(path, "grid axis '" + name + "' holds " + v.dump() +
                                       " (values are strings, numbers or true/false)");
                if (v.is_number_float() && !std::isfinite(v.get<double>()))
                    bad_spec(path, "grid axis '" + name + "' holds a value that is not finite");
                vs.push_back(nlohmann::json::parse(v.dump()));
            }
            for (size_t a = 0; a < vs.size(); ++a)
                for (size_t b = a + 1; b < vs.size(); ++b)
                    if (vs[a] == vs[b]) bad_spec(path, "grid axis '" + name + "' lists " + vs[a].dump() + " twice");
            if (name == "--json" || name == "-q" || name == "--quiet")
                bad_spec(path, "grid axis '" + name + "' is set by the sweep itself");
            s.grid.emplace_back(name, std::move(vs));
        }
    }
    for (const std::string& a : s.args)
        if (a == "--json" || a == "-q" || a == "--quiet")
            bad_spec(path, "\"args\" holds " + a + ", which the sweep sets itself");
    if (j.contains("repetitions")) {
        if (!j["repetitions"].is_number_integer() || j["repetitions"].get<int64_t>() < 1 ||
            j["repetitions"].get<int64_t>() > 1000)
            bad_spec(path, "\"repetitions\" must be a whole number from 1 to 1000");
        s.repetitions = j["repetitions"].get<int>();
    }
    if (j.contains("device")) {
        if (!j["device"].is_string() || (j["device"] != "cpu" && j["device"] != "gpu"))
            bad_spec(path, "\"device\" must be \"cpu\" or \"gpu\" (the workers the cells run on)");
        s.device = j["device"].get<std::string>();
    }
    return s;
}

std::vector<Cell> expand(const Spec& spec) {
    size_t per_rep = spec.scenes.size();
    for (const auto& axis : spec.grid) per_rep *= axis.second.size();
    std::vector<Cell> cells;
    cells.reserve(per_rep * size_t(spec.repetitions));
    for (int rep = 0; rep < spec.repetitions; ++rep) {
        for (size_t i = 0; i < per_rep; ++i) {
            // Mixed-radix digits of i: the scene, then each axis (the last axis fastest).
            std::vector<size_t> digit(spec.grid.size());
            size_t rest = i;
            for (size_t a = spec.grid.size(); a-- > 0;) {
                digit[a] = rest % spec.grid[a].second.size();
                rest /= spec.grid[a].second.size();
            }
            Cell c;
            c.index = cells.size();
            c.rep = rep;
            c.scene = spec.scenes[rest];
            c.args = {spec.command, c.scene};
            for (const std::string& a : spec.args) c.args.push_back(substitute(a, c.index, rep));
            nlohmann::json options = nlohmann::json::object();
            std::string label = spec.command + " " + c.scene;
            for (size_t a = 0; a < spec.grid.size(); ++a) {
                const std::string& name = spec.grid[a].first;
                const nlohmann::json& v = spec.grid[a].second[digit[a]];
                options[name] = v;
                if (v.is_boolean()) {
                    if (v.get<bool>()) c.args.push_back(name);
                    label += v.get<bool>() ? " " + name : " (no " + name + ")";
                } else {
                    c.args.push_back(name);
                    c.args.push_back(substitute(value_text(v), c.index, rep));
                    label += " " + name + " " + value_text(v);
                }
            }
            c.gpu = spec.device.empty() ? needs_gpu(c.args) : spec.device == "gpu";
            c.args.push_back("--json");
            c.args.push_back("-q");
            c.label = label + (spec.repetitions > 1 ? " (rep " + std::to_string(rep + 1) + ")" : "");
            c.key = nlohmann::json{
                {"command", spec.command},
                {"scene", c.scene},
                {"options", options},
                {"args", spec.args},
                {"rep",
                 rep}}.dump();
            cells.push_back(std::move(c));
        }
    }
    return cells;
}

bool Progress::has(const std::string& key) const { return std::binary_search(done.begin(), done.end(), key); }

std::vector<std::string> part_files(const std::string& results) {
    std::vector<std::string> out;
    const fs::path p(results);
    const fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path(".");
    const std::string prefix = p.filename().string() + ".part-";
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(dir, ec))
        if (e.path().filename().string().rfind(prefix, 0) == 0 && e.is_regular_file())
            out.push_back((p.has_parent_path() ? dir / e.path().filename() : e.path().filename()).string());
    std::sort(out.begin(), out.end());
    return out;
}

Progress read_progress(const std::string& results, const std::string& commit) {
    Progress p;
    std::vector<std::string> files;
    if (fs::exists(results)) files.push_back(results);
    for (const std::string& f : part_files(results)) files.push_back(f);
    for (const std::string& f : files) {
        if (fs::is_directory(f)) throw Error("the results file '" + f + "' is a folder");
        std::ifstream in(f);
        if (!in) throw Error("the results file '" + f + "' cannot be read");
        p.files.push_back(f);
        std::string line;
        size_t number = 0;
        while (std::getline(in, line)) {
            ++number;
            if (line.empty()) continue;
            const nlohmann::json j = nlohmann::json::parse(line, nullptr, false);
            if (j.is_discarded() || !j.is_object()) {
                // A line cut short by a full disk or a kill is the last one; anything else is damage.
                if (in.peek() == EOF) {
                    std::fprintf(stderr,
                                 "[bvhlab] warning: '%s': line %zu is not a JSON object (a cut-off write?); ignored\n",
                                 f.c_str(), number);
                    continue;
                }
                throw Error("the results file '" + f + "': line " + std::to_string(number) + " is not a JSON object");
            }
            ++p.records;
            const auto s = j.find("sweep");
            if (s == j.end() || !s->is_object() || !s->contains("key") || !(*s)["key"].is_string()) {
                ++p.foreign_records;
                continue;
            }
            if (j.value("commit", std::string()) != commit) {
                ++p.other_commit_records;
                continue;
            }
            p.done.push_back((*s)["key"].get<std::string>());
        }
    }
    std::sort(p.done.begin(), p.done.end());
    p.done.erase(std::unique(p.done.begin(), p.done.end()), p.done.end());
    return p;
}

ChildResult run_child(const std::string& program, const std::vector<std::string>& args,
                      const std::vector<std::string>& extra_env) {
    // Everything the child needs is built before fork: between fork and exec a threaded
    // process may only make async-signal-safe calls.
    std::vector<std::string> argv_s{program};
    argv_s.insert(argv_s.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (std::string& a : argv_s) argv.push_back(a.data());
    argv.push_back(nullptr);
    std::vector<std::string> env_s;
    for (char** e = environ; *e; ++e) {
        const std::string entry = *e;
        const std::string name = entry.substr(0, entry.find('='));
        const bool replaced = std::any_of(extra_env.begin(), extra_env.end(),
                                          [&](const std::string& x) { return x.substr(0, x.find('=')) == name; });
        if (!replaced) env_s.push_back(entry);
    }
    env_s.insert(env_s.end(), extra_env.begin(), extra_env.end());
    std::vector<char*> envp;
    for (std::string& e : env_s) envp.push_back(e.data());
    envp.push_back(nullptr);
    std::vector<std::string> path_dirs;
    if (program.find('/') == std::string::npos) {
        std::stringstream ss(getenv("PATH") ? getenv("PATH") : "/usr/bin:/bin");
        for (std::string d; std::getline(ss, d, ':');) path_dirs.push_back((d.empty() ? "." : d) + "/" + program);
    } else {
        path_dirs.push_back(program);
    }

    int out_pipe[2], err_pipe[2];
    if (pipe2(out_pipe, O_CLOEXEC) != 0 || pipe2(err_pipe, O_CLOEXEC) != 0)
        throw Error(std::string("cannot start '") + program + "': " + std::strerror(errno));
    const pid_t parent = getpid();
    const pid_t pid = fork();
    if (pid < 0) throw Error(std::string("cannot start '") + program + "': " + std::strerror(errno));
    if (pid == 0) {
        prctl(PR_SET_PDEATHSIG, SIGKILL);  // a sweep killed with -9 takes its cells with it
        if (getppid() != parent) _exit(127);
        dup2(out_pipe[1], 1);
        dup2(err_pipe[1], 2);
        for (const std::string& p : path_dirs) execve(p.c_str(), argv.data(), envp.data());
        const char msg[] = "cannot execute the program\n";
        (void)!::write(2, msg, sizeof msg - 1);
        _exit(127);
    }
    close(out_pipe[1]);
    close(err_pipe[1]);
    ChildResult r;
    std::string err;
    pollfd fds[2] = {{out_pipe[0], POLLIN, 0}, {err_pipe[0], POLLIN, 0}};
    int open_fds = 2;
    char buf[65536];
    while (open_fds > 0) {
        if (poll(fds, 2, -1) < 0) {
            if (errno == EINTR) continue;
            break;
        }
        for (int i = 0; i < 2; ++i) {
            if (fds[i].fd < 0 || !(fds[i].revents & (POLLIN | POLLHUP | POLLERR))) continue;
            const ssize_t n = ::read(fds[i].fd, buf, sizeof buf);
            if (n > 0) {
                (i == 0 ? r.out : err).append(buf, size_t(n));
                if (i == 1 && err.size() > (1u << 16)) err.erase(0, err.size() - (1u << 15));
            } else if (n == 0 || errno != EINTR) {
                close(fds[i].fd);
                fds[i].fd = -1;
                --open_fds;
            }
        }
    }
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    while (!err.empty() && (err.back() == '\n' || err.back() == '\r' || err.back() == ' ')) err.pop_back();
    r.err_tail = err.substr(err.rfind('\n') == std::string::npos ? 0 : err.rfind('\n') + 1);
    return r;
}

RunSummary run(const Spec& spec, const std::vector<Cell>& cells, const RunOptions& opts) {
    const auto t0 = std::chrono::steady_clock::now();
    const auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
    const size_t gpu_cells = size_t(std::count_if(cells.begin(), cells.end(), [](const Cell& c) { return c.gpu; }));
    if (gpu_cells && opts.gpus.empty())
        throw Error("the sweep has " + std::to_string(gpu_cells) + " GPU cells left and this machine has no GPU");

    const int fd = ::open(opts.results.c_str(), O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0) throw Error("cannot open the results file '" + opts.results + "': " + std::strerror(errno));
    std::mutex mutex;  // the results file, the counters and stderr
    RunSummary sum;
    std::atomic<size_t> next_gpu{0}, next_cpu{0};
    std::vector<const Cell*> gpu_queue, cpu_queue;
    for (const Cell& c : cells) (c.gpu ? gpu_queue : cpu_queue).push_back(&c);
    std::string fatal;

    const auto worker = [&](const std::vector<const Cell*>& queue, std::atomic<size_t>& next, std::string gpu) {
        for (size_t i; (i = next++) < queue.size();) {
            {
                std::lock_guard<std::mutex> lock(mutex);
                if (!fatal.empty()) return;
            }
            const Cell& c = *queue[i];
            std::vector<std::string> env;
            if (!gpu.empty()) env.push_back("CUDA_VISIBLE_DEVICES=" + gpu);
            const auto c0 = std::chrono::steady_clock::now();
            const ChildResult r = run_child(opts.exe, c.args, env);
            const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - c0).count();
            std::string lines, why;
            size_t records = 0;
            if (r.exit_code == 0) {
                std::stringstream ss(r.out);
                for (std::string line; std::getline(ss, line);) {
                    if (line.empty()) continue;
                    nlohmann::json j = nlohmann::json::parse(line, nullptr, false);
                    if (j.is_discarded() || !j.is_object()) {
                        why = "printed a line that is not a JSON object";
                        break;
                    }
                    j["sweep"] = {{"key", c.key},
                                  {"spec", spec.name},
                                  {"cell", c.index},
                                  {"rep", c.rep},
                                  {"argv", c.args},
                                  {"seconds", secs},
                                  {"gpu", gpu.empty() ? nlohmann::json() : nlohmann::json(gpu)}};
                    lines += j.dump() + "\n";
                    ++records;
                }
                if (why.empty() && records == 0) why = "printed no record";
            } else {
                why = "exit " + std::to_string(r.exit_code) + (r.err_tail.empty() ? "" : ": " + r.err_tail);
            }
            std::lock_guard<std::mutex> lock(mutex);
            if (why.empty()) {
                try {
                    write_all(fd, lines, opts.results);  // one write per cell: no half cell after a kill
                } catch (const Error& e) {
                    fatal = e.what();
                    return;
                }
                ++sum.ran;
            } else {
                ++sum.failed;
                std::fprintf(stderr, "[bvhlab] sweep: cell %zu failed (%s): %s\n", c.index, c.label.c_str(),
                             why.c_str());
            }
            const size_t finished = sum.ran + sum.failed;
            if (!opts.quiet) {
                const double t = elapsed();
                std::fprintf(stderr, "[bvhlab] sweep: %zu of %zu cells (%zu failed), %s, about %s left: %s%s\n",
                             finished, cells.size(), sum.failed, format_duration(t).c_str(),
                             format_duration(t / double(finished) * double(cells.size() - finished)).c_str(),
                             c.label.c_str(), gpu.empty() ? "" : (" on GPU " + gpu).c_str());
            }
        }
    };
    std::vector<std::thread> threads;
    if (!gpu_queue.empty())
        for (const std::string& g : opts.gpus)
            threads.emplace_back(worker, std::cref(gpu_queue), std::ref(next_gpu), g);
    if (!cpu_queue.empty())
        for (int j = 0; j < std::max(1, opts.jobs); ++j)
            threads.emplace_back(worker, std::cref(cpu_queue), std::ref(next_cpu), std::string());
    for (std::thread& t : threads) t.join();
    ::close(fd);
    if (!fatal.empty()) throw Error(fatal);
    sum.seconds = elapsed();
    return sum;
}

size_t merge_parts(const std::string& results) {
    const std::vector<std::string> parts = part_files(results);
    if (parts.empty()) return 0;
    // Keys already in the results file (at any commit: a record names its own commit, and the
    // pair is what counts).
    std::vector<std::string> have;
    std::string text;
    const auto key_of = [](const nlohmann::json& j) {
        const auto s = j.find("sweep");
        return (s != j.end() && s->is_object() && s->contains("key"))
                   ? j.value("commit", std::string()) + "\n" + (*s)["key"].dump()
                   : std::string();
    };
    if (fs::exists(results)) {
        std::ifstream in(results);
        for (std::string line; std::getline(in, line);) {
            if (line.empty()) continue;
            const nlohmann::json j = nlohmann::json::parse(line, nullptr, false);
            if (j.is_discarded()) continue;  // a cut-off last line is dropped by the rewrite
            have.push_back(key_of(j));
            text += line + "\n";
        }
    }
    std::sort(have.begin(), have.end());
    std::vector<std::string> added;
    for (const std::string& part : parts) {
        std::ifstream in(part);
        for (std::string line; std::getline(in, line);) {
            if (line.empty()) continue;
            const nlohmann::json j = nlohmann::json::parse(line, nullptr, false);
            if (j.is_discarded()) continue;
            const std::string k = key_of(j);
            if (!k.empty() && std::binary_search(have.begin(), have.end(), k)) continue;
            if (!k.empty()) added.push_back(k);
            text += line + "\n";
        }
    }
    scene::write_file_atomically(results, [&](std::FILE* f) {
        if (std::fwrite(text.data(), 1, text.size(), f) != text.size())
            throw Error("cannot write the results file '" + results + "'");
    });
    for (const std::string& part : parts) fs::remove(part);
    std::sort(added.begin(), added.end());
    return size_t(std::unique(added.begin(), added.end()) - added.begin());
}

}  // namespace bvhlab::cli::sweep
