// SPDX-License-Identifier: MIT
// Each subcommand registers itself on the app; its callback does the work and may throw
// bvhlab::Error, which main turns into a one-line message and a non-zero exit.
#pragma once

#include <CLI/CLI.hpp>

#include "tools/bvhlab/context.h"

namespace bvhlab::cli {

/// Set by a subcommand that found a real problem in its results (a verify mismatch).
extern int g_exit_code;

struct Built;
/// Human-readable build figures (the `build` table), also used by `run`.
void print_build_table(const Scene& s, const Built& b);

void register_build(CLI::App& app, Globals& g);
void register_rays(CLI::App& app, Globals& g);
void register_bench(CLI::App& app, Globals& g);
void register_verify(CLI::App& app, Globals& g);
void register_gen(CLI::App& app, Globals& g);
void register_run(CLI::App& app, Globals& g);
void register_quality(CLI::App& app, Globals& g);
void register_kernels(CLI::App& app, Globals& g);
void register_cache(CLI::App& app, Globals& g);
void register_render(CLI::App& app, Globals& g);
void register_sweep(CLI::App& app, Globals& g);
void register_rerun(CLI::App& app, Globals& g);
void register_report(CLI::App& app, Globals& g);

}  // namespace bvhlab::cli
