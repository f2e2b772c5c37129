// SPDX-License-Identifier: MIT
// Fuzz target: the ray-file reader. Every ray it returns must be traceable.
#include "tests/fuzz/fuzz_support.h"
#include "traversal/rays/ray_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string path = bvhlab::fuzz::write_input(data, size, "input.rays");
    return bvhlab::fuzz::expect_success_or_error([&] {
        const bvhlab::trav::RaySet set = bvhlab::trav::read_ray_file(path);
        for (const bvhlab::trav::Ray& r : set.rays)
            if (!bvhlab::trav::invalid_ray(r).empty()) __builtin_trap();
    });
}
