// SPDX-License-Identifier: MIT
// CPU tracer for kd-trees: the shared kd traversal over a ray set, in parallel with TBB.
#pragma once

#include <vector>

#include "accel/layouts/kd_convert.h"
#include "traversal/device/bvh2_traverse.h"
#include "traversal/device/ray.h"

namespace bvhlab::trav {

/// Traces every ray with a full stack (stack_limit = 64) or a short stack with restart
/// (1..8); fills `counters` too when it is non-null. Throws bvhlab::Error for another stack
/// size, or a tree deeper than the full stack.
/// Throws bvhlab::Error for a stack size other than 64 or 1..8, or a tree deeper than the
/// full stack.
void check_kd_stack(const accel::KdLayout& kd, int stack_limit);

void trace_kd_cpu(const accel::KdLayout& kd, int stack_limit, const std::vector<Ray>& rays, Query query,
                  std::vector<Hit>& hits, std::vector<TraversalCounters>* counters = nullptr);

}  // namespace bvhlab::trav
