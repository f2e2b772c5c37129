// SPDX-License-Identifier: MIT
// CPU tracer: the shared BVH2 traversal run over a ray set in parallel with TBB.
#pragma once

#include <functional>
#include <vector>

#include "accel/layouts/bvh2_node.h"
#include "traversal/device/bvh2_traverse.h"
#include "traversal/device/ray.h"

namespace bvhlab::trav {

/// Called now and then with the number of rays finished so far; may be empty.
using ProgressFn = std::function<void(size_t done, size_t total)>;

/// Traces every ray (closest or any hit) into `hits`, which is resized to rays.size().
void trace_cpu(const accel::Bvh2& bvh, const std::vector<Ray>& rays, Query query,
               std::vector<Hit>& hits, const ProgressFn& progress = {});

/// Like trace_cpu, and also returns the per-ray work counters.
void trace_cpu_counted(const accel::Bvh2& bvh, const std::vector<Ray>& rays, Query query,
                       std::vector<Hit>& hits, std::vector<TraversalCounters>& counters);

}  // namespace bvhlab::trav
