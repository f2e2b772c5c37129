// SPDX-License-Identifier: MIT
// Fuzz target: a scene-cache entry, parsed whole as `bvhlab cache info` does (a damaged entry is
// listed as unusable, never a crash).
#include <filesystem>

#include "scene/io/scene_cache.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace bvhlab;
    static const std::filesystem::path dir = [] {
        const auto d = std::filesystem::path(fuzz::write_input(nullptr, 0, "cache_root")).parent_path() / "cache";
        std::filesystem::create_directories(d);
        return d;
    }();
    (void)fuzz::write_input(data, size, "cache/input.bvhscene");
    return fuzz::expect_success_or_error([&] { (void)scene::list_scene_cache(dir.string()); });
}
