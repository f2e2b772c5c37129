// SPDX-License-Identifier: MIT
// Fuzz target: scene files through Assimp. The first byte picks the extension (glTF, GLB, PLY,
// STL), the rest is the file. A load either throws bvhlab::Error or gives meshes whose indices,
// corner normals, texture coordinates and material ids are in range, placed by instances that
// name existing meshes.
#include "scene/io/scene_file.h"
#include "scene/scene.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size == 0) return 0;
    static const char* const kExtension[] = {"input.gltf", "input.glb", "input.ply", "input.stl"};
    const std::string path = bvhlab::fuzz::write_input(data + 1, size - 1, kExtension[data[0] % 4]);
    return bvhlab::fuzz::expect_success_or_error([&] {
        const bvhlab::scene::InstancedScene s = bvhlab::scene::load_assimp(path);
        for (const bvhlab::scene::TriangleMesh& m : s.meshes) {
            const size_t n = m.triangle_count();
            for (uint32_t i : m.indices)
                if (i >= m.vertices.size()) __builtin_trap();
            if (!m.normals.empty() && m.normals.size() != 3 * n) __builtin_trap();
            if (!m.texcoords.empty() && m.texcoords.size() != 6 * n) __builtin_trap();
            if (m.material_ids.size() != n) __builtin_trap();
            for (int32_t id : m.material_ids)
                if (id < -1 || (id >= 0 && size_t(id) >= s.materials.size())) __builtin_trap();
        }
        for (const bvhlab::scene::Instance& inst : s.instances)
            if (inst.mesh >= s.meshes.size()) __builtin_trap();
    });
}
