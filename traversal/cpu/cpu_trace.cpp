// SPDX-License-Identifier: MIT
#include "traversal/cpu/cpu_trace.h"

#include <tbb/parallel_for.h>

#include <string>

#include "accel/core/check.h"

namespace bvhlab::trav {
namespace {

/// `kCount` is a template parameter so the uncounted path passes a literal nullptr and the
/// traversal's counter branches compile away.
template <bool kCount>
void trace_all(const accel::Bvh2& bvh, const std::vector<Ray>& rays, Query query, std::vector<Hit>& hits,
               std::vector<TraversalCounters>* counters) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.size(), 1024), [&](const auto& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
            TraversalCounters* c = kCount ? &(*counters)[i] : nullptr;
            hits[i] = query == Query::kAny
                          ? traverse_bvh2<true>(bvh.nodes.data(), bvh.tris.data(), bvh.tri_ids.data(), rays[i], c)
                          : traverse_bvh2<false>(bvh.nodes.data(), bvh.tris.data(), bvh.tri_ids.data(), rays[i], c);
        }
    });
}

}  // namespace

void check_bvh2_stack(const accel::Bvh2& bvh) {
    if (bvh.depth > uint32_t(kBvh2StackSize))
        throw Error("BVH of depth " + std::to_string(bvh.depth) + " is deeper than the traversal stack of " +
                    std::to_string(kBvh2StackSize) + " entries");
}

void trace_cpu(const accel::Bvh2& bvh, const std::vector<Ray>& rays, Query query, std::vector<Hit>& hits,
               std::vector<TraversalCounters>* counters) {
    check_bvh2_stack(bvh);
    hits.resize(rays.size());
    if (counters) {
        counters->assign(rays.size(), TraversalCounters{});
        trace_all<true>(bvh, rays, query, hits, counters);
    } else {
        trace_all<false>(bvh, rays, query, hits, nullptr);
    }
}

}  // namespace bvhlab::trav
