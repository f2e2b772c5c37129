// SPDX-License-Identifier: MIT
#include "traversal/cpu/cpu_trace.h"

#include <tbb/parallel_for.h>

#include <string>
#include <type_traits>

#include "accel/core/check.h"

namespace bvhlab::trav {
namespace {

/// `kCount` is a template parameter so the uncounted path passes a literal nullptr and the
/// traversal's counter branches compile away. `trace(any, ray, counters)` traces one ray.
template <bool kCount, class Trace>
void trace_all(const std::vector<Ray>& rays, Query query, std::vector<Hit>& hits,
               std::vector<TraversalCounters>* counters, const Trace& trace) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.size(), 1024), [&](const auto& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
            TraversalCounters* c = kCount ? &(*counters)[i] : nullptr;
            hits[i] = query == Query::kAny ? trace(std::true_type{}, rays[i], c) : trace(std::false_type{}, rays[i], c);
        }
    });
}

/// Sizes the outputs and runs trace_all with or without counters.
template <class Trace>
void trace_set(const std::vector<Ray>& rays, Query query, std::vector<Hit>& hits,
               std::vector<TraversalCounters>* counters, const Trace& trace) {
    hits.resize(rays.size());
    if (counters) {
        counters->assign(rays.size(), TraversalCounters{});
        trace_all<true>(rays, query, hits, counters, trace);
    } else {
        trace_all<false>(rays, query, hits, nullptr, trace);
    }
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
    trace_set(rays, query, hits, counters, [&](auto any, const Ray& ray, TraversalCounters* c) {
        return traverse_bvh2<decltype(any)::value>(bvh.nodes.data(), bvh.tris.data(), bvh.tri_ids.data(), ray, c);
    });
}

void check_cwbvh_stack(const accel::Cwbvh& cw) {
    if (cw.depth > uint32_t(kCwbvhStackSize))
        throw Error("CWBVH of depth " + std::to_string(cw.depth) + " is deeper than the traversal stack of " +
                    std::to_string(kCwbvhStackSize) + " entries");
}

void trace_cpu(const accel::Cwbvh& cw, const std::vector<Ray>& rays, Query query, std::vector<Hit>& hits,
               std::vector<TraversalCounters>* counters) {
    check_cwbvh_stack(cw);
    const CwbvhView view{cw.nodes.data(), cw.tris.data(), cw.tri_ids.data(), cw.vtris.data()};
    if (cw.tri_format == accel::CwTris::kVertices) {
        trace_set(rays, query, hits, counters, [&](auto any, const Ray& ray, TraversalCounters* c) {
            return traverse_cwbvh<decltype(any)::value, true>(view, ray, c);
        });
    } else {
        trace_set(rays, query, hits, counters, [&](auto any, const Ray& ray, TraversalCounters* c) {
            return traverse_cwbvh<decltype(any)::value, false>(view, ray, c);
        });
    }
}

void trace_cpu(const accel::TwoLevelBvh& bvh, const std::vector<Ray>& rays, Query query, std::vector<Hit>& hits,
               std::vector<TraversalCounters>* counters) {
    check_bvh2_stack(bvh.tlas);
    if (bvh.wide()) {
        std::vector<CwbvhView> blas(bvh.cw_blas.size());
        bool vertices = false;
        for (size_t m = 0; m < bvh.cw_blas.size(); ++m) {
            const accel::Cwbvh& cw = bvh.cw_blas[m];
            check_cwbvh_stack(cw);
            blas[m] = {cw.nodes.data(), cw.tris.data(), cw.tri_ids.data(), cw.vtris.data()};
            vertices = vertices || cw.tri_format == accel::CwTris::kVertices;
        }
        check_cwbvh_stack(bvh.cw_tlas);
        TwoLevelView view{
            bvh.tlas.nodes.data(), bvh.tlas.tri_ids.data(), bvh.instances.data(), nullptr, blas.data(), vertices};
        view.cw_tlas = bvh.cw_tlas.nodes.data();
        view.cw_tlas_ids = bvh.cw_tlas.tri_ids.data();
        trace_set(rays, query, hits, counters, [&](auto any, const Ray& ray, TraversalCounters* c) {
            return view.cw_vertices ? traverse_two_level_cwbvh<decltype(any)::value, true>(view, ray, c)
                                    : traverse_two_level_cwbvh<decltype(any)::value, false>(view, ray, c);
        });
        return;
    }
    std::vector<Bvh2View> blas(bvh.blas.size());
    for (size_t m = 0; m < bvh.blas.size(); ++m) {
        check_bvh2_stack(bvh.blas[m]);
        blas[m] = {bvh.blas[m].nodes.data(), bvh.blas[m].tris.data(), bvh.blas[m].tri_ids.data()};
    }
    const TwoLevelView view{bvh.tlas.nodes.data(), bvh.tlas.tri_ids.data(), bvh.instances.data(), blas.data()};
    trace_set(rays, query, hits, counters, [&](auto any, const Ray& ray, TraversalCounters* c) {
        return traverse_two_level<decltype(any)::value>(view, ray, c);
    });
}

}  // namespace bvhlab::trav
