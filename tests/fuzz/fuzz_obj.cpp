// SPDX-License-Identifier: MIT
// Fuzz target: the OBJ loader (tinyobjloader behind bvhlab's strict pre-scan and cleanup).
#include "scene/io/obj_loader.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string path = bvhlab::fuzz::write_input(data, size, "input.obj");
    return bvhlab::fuzz::expect_success_or_error([&] {
        const bvhlab::scene::TriangleMesh m = bvhlab::scene::load_obj(path);
        // What the loader promises: triangles with ids in range.
        for (uint32_t i : m.indices)
            if (i >= m.vertices.size()) __builtin_trap();
    });
}
