// SPDX-License-Identifier: MIT
#include "accel/core/prim_ref.h"

#include <tbb/parallel_for.h>

namespace bvhlab::accel {

std::vector<PrimRef> make_prim_refs(const scene::TriangleMesh& mesh) {
    std::vector<PrimRef> refs(mesh.triangle_count());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, refs.size(), 16384), [&](const auto& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) refs[i] = {mesh.triangle_bounds(i), uint32_t(i)};
    });
    return refs;
}

}  // namespace bvhlab::accel
