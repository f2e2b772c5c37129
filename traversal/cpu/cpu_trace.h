// SPDX-License-Identifier: MIT
// CPU tracer: the shared BVH2 traversal run over a ray set in parallel with TBB.
#pragma once

#include <vector>

#include "accel/layouts/bvh2_node.h"
#include "traversal/device/bvh2_traverse.h"
#include "traversal/device/ray.h"

namespace bvhlab::trav {

/// Traces every ray (closest or any hit) into `hits`, resized to rays.size(). With a non-null
/// `counters`, also records each ray's work (nodes, leaves, triangle tests). Throws
/// bvhlab::Error for a tree deeper than the stack (kBvh2StackSize).
/// Throws bvhlab::Error when `bvh` is deeper than the traversal stack (kBvh2StackSize).
void check_bvh2_stack(const accel::Bvh2& bvh);

void trace_cpu(const accel::Bvh2& bvh, const std::vector<Ray>& rays, Query query, std::vector<Hit>& hits,
               std::vector<TraversalCounters>* counters = nullptr);

}  // namespace bvhlab::trav
