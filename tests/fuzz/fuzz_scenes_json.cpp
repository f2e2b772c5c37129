// SPDX-License-Identifier: MIT
// Fuzz target: the scene catalogue (scenes.json). Every entry it returns names a file inside
// its folder.
#include <filesystem>

#include "tests/fuzz/fuzz_support.h"
#include "traversal/rays/scene_catalogue.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string path = bvhlab::fuzz::write_input(data, size, "scenes.json");
    const std::string dir = std::filesystem::path(path).parent_path().string();
    return bvhlab::fuzz::expect_success_or_error([&] {
        for (const auto& e : bvhlab::trav::read_catalogue(dir)) {
            const auto rel = std::filesystem::path(e.file).lexically_relative(dir).lexically_normal();
            if (rel.empty() || *rel.begin() == "..") __builtin_trap();
        }
    });
}
