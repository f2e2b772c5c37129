// SPDX-License-Identifier: MIT
// `bvhlab report RESULTS... --out DIR`: tables and plots from result files. The work is
// tools/report.py (Python: matplotlib draws the plots); this command finds it and runs it with
// the same arguments, so that `bvhlab report --help` and its errors are the script's.
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include "accel/core/check.h"
#include "tools/bvhlab/commands.h"

namespace bvhlab::cli {

namespace fs = std::filesystem;

/// tools/report.py in the source tree, or share/bvhlab/report.py beside an installed bin/;
/// $BVHLAB_REPORT names another.
std::string report_script() {
    if (const char* env = std::getenv("BVHLAB_REPORT"); env && *env) return env;
    std::error_code ec;
    if (fs::exists(BVHLAB_SOURCE_DIR "/tools/report.py", ec)) return BVHLAB_SOURCE_DIR "/tools/report.py";
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    return (exe.parent_path().parent_path() / "share" / "bvhlab" / "report.py").string();
}

void register_report(CLI::App& app, Globals&) {
    auto args = std::make_shared<std::vector<std::string>>();
    CLI::App* sub = app.add_subcommand(
        "report",
        "merge result files into Markdown tables and plots: RESULTS... --out DIR [--baseline TRACER] "
        "[--compare A B] [--no-plots] (Python with matplotlib; `bvhlab report --help` lists the options)");
    sub->allow_extras();
    sub->prefix_command();
    sub->set_help_flag();  // --help is the script's
    sub->callback([sub] {
        const std::string script = report_script();
        if (!fs::exists(script))
            throw Error("the report script '" + script + "' is missing (set BVHLAB_REPORT to tools/report.py)");
        // Debian's python3, which tools/install_deps.sh gives matplotlib, unless $BVHLAB_PYTHON
        // names another (a virtual environment's, say).
        std::string python = "python3";
        if (const char* env = std::getenv("BVHLAB_PYTHON"); env && *env)
            python = env;
        else if (fs::exists("/usr/bin/python3"))
            python = "/usr/bin/python3";
        std::vector<std::string> words{python, script};
        for (const std::string& a : sub->remaining()) words.push_back(a);
        if (words.size() == 3 && words[2] == "--") words.pop_back();
        std::vector<char*> argv;
        for (std::string& w : words) argv.push_back(w.data());
        argv.push_back(nullptr);
        std::fflush(stdout);
        execvp(python.c_str(), argv.data());
        throw Error("cannot run " + python + " for the report: " + std::strerror(errno));
    });
}

}  // namespace bvhlab::cli
