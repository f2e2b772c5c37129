// SPDX-License-Identifier: MIT
// Fuzz target: the hit-file reader and the triangle-id check against a 1000-triangle scene of
// three instances (the second of an empty mesh).
#include "tests/fuzz/fuzz_support.h"
#include "traversal/rays/ray_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string path = bvhlab::fuzz::write_input(data, size, "input.hits");
    return bvhlab::fuzz::expect_success_or_error([&] {
        const bvhlab::trav::HitSet set = bvhlab::trav::read_hit_file(path);
        bvhlab::trav::check_hit_ids(set, {0, 400, 400, 1000}, path);
        for (const bvhlab::trav::Hit& h : set.hits)
            if (h.tri < -1 || h.tri >= 1000) __builtin_trap();
    });
}
