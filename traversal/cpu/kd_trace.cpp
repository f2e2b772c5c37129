// SPDX-License-Identifier: MIT
#include "traversal/cpu/kd_trace.h"

#include <tbb/parallel_for.h>

#include "accel/core/check.h"
#include "traversal/device/kd_traverse.h"

namespace bvhlab::trav {

KdTracer::KdTracer(accel::KdTree t, const accel::TriangleMesh& mesh, int stack)
    : tree(std::move(t)), stack_limit(stack) {
    BVHLAB_CHECK(stack_limit == kKdFullStack || (stack_limit >= 1 && stack_limit <= kKdMaxShortStack),
                 "kd-tree stack depth must be 1..8 (short stack) or 64 (full stack)");
    tris.resize(mesh.triangle_count());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, tris.size(), 4096), [&](const auto& r) {
        for (size_t i = r.begin(); i < r.end(); ++i)
            tris[i] = accel::make_woop_triangle(mesh.vertex(i, 0), mesh.vertex(i, 1), mesh.vertex(i, 2));
    });
}

void trace_kd_cpu(const KdTracer& kd, const std::vector<Ray>& rays, Query query, std::vector<Hit>& hits,
                  std::vector<TraversalCounters>* counters) {
    hits.resize(rays.size());
    if (counters) counters->assign(rays.size(), TraversalCounters{});
    const KdView view{kd.tree.nodes.data(), kd.tree.prim_indices.data(), kd.tris.data(), kd.tree.bounds};
    const bool full = kd.stack_limit == kKdFullStack;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.size(), 1024), [&](const auto& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
            TraversalCounters* c = counters ? &(*counters)[i] : nullptr;
            if (query == Query::kAny) {
                hits[i] = full ? traverse_kd<true, kKdFullStack>(view, rays[i], kd.stack_limit, c)
                               : traverse_kd<true, kKdMaxShortStack>(view, rays[i], kd.stack_limit, c);
            } else {
                hits[i] = full ? traverse_kd<false, kKdFullStack>(view, rays[i], kd.stack_limit, c)
                               : traverse_kd<false, kKdMaxShortStack>(view, rays[i], kd.stack_limit, c);
            }
        }
    });
}

}  // namespace bvhlab::trav
