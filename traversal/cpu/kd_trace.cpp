// SPDX-License-Identifier: MIT
#include "traversal/cpu/kd_trace.h"

#include <tbb/parallel_for.h>

#include <string>

#include "accel/core/check.h"
#include "traversal/device/kd_traverse.h"

namespace bvhlab::trav {

void check_kd_stack(const accel::KdLayout& kd, int stack_limit) {
    const bool full = stack_limit == kKdFullStack;
    if (!full && (stack_limit < 1 || stack_limit > kKdMaxShortStack))
        throw Error("kd-tree stack depth must be 1..8 (short stack) or 64 (full stack), not " +
                    std::to_string(stack_limit));
    if (full && kd.depth > uint32_t(kKdFullStack))
        throw Error("kd-tree of depth " + std::to_string(kd.depth) + " is deeper than the full stack of " +
                    std::to_string(kKdFullStack) + " entries");
}

void trace_kd_cpu(const accel::KdLayout& kd, int stack_limit, const std::vector<Ray>& rays, Query query,
                  std::vector<Hit>& hits, std::vector<TraversalCounters>* counters) {
    check_kd_stack(kd, stack_limit);
    const bool full = stack_limit == kKdFullStack;
    hits.resize(rays.size());
    if (counters) counters->assign(rays.size(), TraversalCounters{});
    const KdView view{kd.tree.nodes.data(), kd.tree.prim_indices.data(), kd.tris.data(), kd.tree.bounds};
    tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.size(), 1024), [&](const auto& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
            TraversalCounters* c = counters ? &(*counters)[i] : nullptr;
            if (query == Query::kAny) {
                hits[i] = full ? traverse_kd<true, kKdFullStack>(view, rays[i], stack_limit, c)
                               : traverse_kd<true, kKdMaxShortStack>(view, rays[i], stack_limit, c);
            } else {
                hits[i] = full ? traverse_kd<false, kKdFullStack>(view, rays[i], stack_limit, c)
                               : traverse_kd<false, kKdMaxShortStack>(view, rays[i], stack_limit, c);
            }
        }
    });
}

}  // namespace bvhlab::trav
