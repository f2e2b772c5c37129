// SPDX-License-Identifier: MIT
// `bvhlab kernels`: the GPU kernel registry, one line (or JSON object) per kernel.
#include <cstdio>

#include "tools/bvhlab/commands.h"
#include "traversal/gpu/registry.h"

namespace bvhlab::cli {

void register_kernels(CLI::App& app, Globals& g) {
    CLI::App* sub = app.add_subcommand(
        "kernels",
        "list the GPU kernels: name, layout, whether it is its layout's default, stack, block size, description");
    sub->callback([&g] {
        const auto kernels = trav::registered_kernels();
        if (kernels.empty() && !g.json)
            std::printf("no GPU kernels: this bvhlab was built without CUDA (nvcc was not found at configure time)\n");
        for (const trav::KernelInfo& k : kernels) {
            const std::string stack = k.stack_entries == trav::kNoStackLimit
                                          ? std::string(k.short_stack ? "short, 1-8 + restart" : "unlimited")
                                          : std::to_string(k.stack_entries);
            if (g.json) {
                emit({{"record", "kernel"},
                      {"commit", git_commit()},
                      {"kernel", k.name},
                      {"layout", trav::layout_name(k.layout)},
                      {"stack_entries", stack},
                      {"short_stack", k.short_stack},
                      {"dynamic_fetch", k.dynamic_fetch},
                      {"max_block", k.max_block},
                      {"default_block", k.default_block},
                      {"default", k.is_default},
                      {"description", k.description}});
            } else {
                std::printf("%-28s %-7s %-8s stack %-22s block %4d  %s\n", k.name, trav::layout_name(k.layout),
                            k.is_default ? "default" : "", stack.c_str(), k.default_block, k.description);
            }
        }
    });
}

}  // namespace bvhlab::cli
