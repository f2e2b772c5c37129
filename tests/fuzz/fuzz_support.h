// SPDX-License-Identifier: MIT
// What every fuzz target shares: the input as a file (the readers take paths), and the one
// outcome besides success that the error contract allows, bvhlab::Error. Anything else that
// escapes (another exception type, a crash, a sanitizer report, a hang) is a finding.
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>

#include "accel/core/check.h"

namespace bvhlab::fuzz {

/// A per-process scratch folder; `name` inside it holds the input.
inline std::string write_input(const uint8_t* data, size_t size, const std::string& name) {
    static const std::filesystem::path dir = [] {
        const std::filesystem::path d =
            std::filesystem::temp_directory_path() / ("bvhlab_fuzz_" + std::to_string(::getpid()));
        std::filesystem::create_directories(d);
        return d;
    }();
    const std::string path = (dir / name).string();
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) __builtin_trap();  // the harness itself failed
    if (size) std::fwrite(data, 1, size, f);
    std::fclose(f);
    return path;
}

/// Runs `read`; a bvhlab::Error (a refused input) is a correct outcome.
template <class Read>
int expect_success_or_error(Read&& read) {
    try {
        read();
    } catch (const Error&) {
    }
    return 0;
}

}  // namespace bvhlab::fuzz
