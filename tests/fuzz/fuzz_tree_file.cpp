// SPDX-License-Identifier: MIT
// Fuzz target: the structure-file reader (BVH and kd-tree files), then the validation every
// loaded structure goes through before use (against a stand-in mesh of the header's triangle
// count, when that is small enough to make).
#include "accel/core/validate.h"
#include "accel/io/tree_file.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace bvhlab;
    const std::string path = fuzz::write_input(data, size, "input.tree");
    return fuzz::expect_success_or_error([&] {
        const accel::TreeFile f = accel::read_tree_file(path);
        if (f.meta.kdtree) {
            (void)accel::validate_kd(f.kd, f.meta.triangles);
            return;
        }
        if (f.meta.triangles == 0 || f.meta.triangles > 100000) return;
        scene::TriangleMesh mesh;
        for (uint64_t t = 0; t < f.meta.triangles; ++t) {
            const float x = float(t);
            scene::add_triangle_checked(mesh, {x, 0, 0}, {x + 1, 0, 0}, {x, 1, 0}, -1);
        }
        accel::ValidateOptions v;
        v.allow_duplicates = f.meta.builder == accel::BuilderKind::kSbvh;
        (void)accel::validate(f.tree, mesh, f.meta.options.config, v);
    });
}
