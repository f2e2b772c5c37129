// SPDX-License-Identifier: MIT
#include "traversal/cpu/cpu_trace.h"

#include <tbb/parallel_for.h>

#include <atomic>

namespace bvhlab::trav {

void trace_cpu(const accel::Bvh2& bvh, const std::vector<Ray>& rays, Query query,
               std::vector<Hit>& hits, const ProgressFn& progress) {
    hits.resize(rays.size());
    std::atomic<size_t> done{0};
    const size_t step = std::max<size_t>(rays.size() / 50, 1);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.size(), 1024), [&](const auto& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
            hits[i] = query == Query::kAny
                          ? traverse_bvh2<true>(bvh.nodes.data(), bvh.tris.data(), bvh.tri_ids.data(), rays[i])
                          : traverse_bvh2<false>(bvh.nodes.data(), bvh.tris.data(), bvh.tri_ids.data(), rays[i]);
        }
        if (progress) {
            size_t before = done.fetch_add(r.size());
            if ((before + r.size()) / step != before / step) progress(before + r.size(), rays.size());
        }
    });
}

void trace_cpu_counted(const accel::Bvh2& bvh, const std::vector<Ray>& rays, Query query,
                       std::vector<Hit>& hits, std::vector<TraversalCounters>& counters) {
    hits.resize(rays.size());
    counters.assign(rays.size(), TraversalCounters{});
    tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.size(), 1024), [&](const auto& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
            TraversalCounters* c = &counters[i];
            hits[i] = query == Query::kAny
                          ? traverse_bvh2<true>(bvh.nodes.data(), bvh.tris.data(), bvh.tri_ids.data(), rays[i], c)
                          : traverse_bvh2<false>(bvh.nodes.data(), bvh.tris.data(), bvh.tri_ids.data(), rays[i], c);
        }
    });
}

}  // namespace bvhlab::trav
