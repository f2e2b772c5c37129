// SPDX-License-Identifier: MIT
// Fuzz target: an MTL file, read through an OBJ that names it (the strict number scan, then
// tinyobjloader's parser), and the renderer's check of every material it yields.
#include "scene/io/obj_loader.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace bvhlab;
    (void)fuzz::write_input(data, size, "input.mtl");
    static const std::string obj = [] {
        const char text[] = "mtllib input.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nusemtl m\nf 1/1 2/1 3/1\n";
        return fuzz::write_input(reinterpret_cast<const uint8_t*>(text), sizeof text - 1, "input_mtl.obj");
    }();
    return fuzz::expect_success_or_error([&] {
        const scene::TriangleMesh m = scene::load_obj(obj);
        for (const scene::Material& mat : m.materials) (void)scene::material_problem(mat);
    });
}
