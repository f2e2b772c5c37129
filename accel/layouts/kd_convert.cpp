// SPDX-License-Identifier: MIT
#include "accel/layouts/kd_convert.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <utility>

namespace bvhlab::accel {

KdLayout convert_to_kd_layout(KdTree tree, const scene::TriangleMesh& mesh) {
    KdLayout out;
    out.tree = std::move(tree);
    out.tris.resize(mesh.triangle_count());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, out.tris.size(), 4096), [&](const auto& r) {
        for (size_t i = r.begin(); i < r.end(); ++i)
            out.tris[i] = make_woop_triangle(mesh.vertex(i, 0), mesh.vertex(i, 1), mesh.vertex(i, 2));
    });
    // Children sit side by side at child() and child() + 1.
    std::vector<std::pair<uint32_t, uint32_t>> todo;
    if (!out.tree.nodes.empty()) todo.push_back({0, 0});
    while (!todo.empty()) {
        const auto [node, depth] = todo.back();
        todo.pop_back();
        out.depth = std::max(out.depth, depth);
        const KdNode& n = out.tree.nodes[node];
        if (n.is_leaf()) continue;
        todo.push_back({n.child(), depth + 1});
        todo.push_back({n.child() + 1, depth + 1});
    }
    return out;
}

}  // namespace bvhlab::accel
