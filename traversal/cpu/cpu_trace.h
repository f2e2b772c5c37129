// SPDX-License-Identifier: MIT
// CPU tracers: the shared BVH2 and CWBVH traversals run over a ray set in parallel with TBB.
#pragma once

#include <vector>

#include "accel/layouts/bvh2_node.h"
#include "accel/layouts/cwbvh_node.h"
#include "traversal/device/bvh2_traverse.h"
#include "traversal/device/cwbvh_traverse.h"
#include "traversal/device/ray.h"
#include "traversal/device/two_level_cwbvh_traverse.h"
#include "traversal/device/two_level_traverse.h"

namespace bvhlab::trav {

/// Throws bvhlab::Error when `bvh` is deeper than the traversal stack (kBvh2StackSize).
void check_bvh2_stack(const accel::Bvh2& bvh);
/// Throws bvhlab::Error when `cw` is deeper than the traversal stack (kCwbvhStackSize).
void check_cwbvh_stack(const accel::Cwbvh& cw);

/// Traces every ray (closest or any hit) into `hits`, resized to rays.size(). With a non-null
/// `counters`, also records each ray's work (nodes, leaves, triangle tests). Throws
/// bvhlab::Error for a tree deeper than the stack.
void trace_cpu(const accel::Bvh2& bvh, const std::vector<Ray>& rays, Query query, std::vector<Hit>& hits,
               std::vector<TraversalCounters>* counters = nullptr);
void trace_cpu(const accel::Cwbvh& cw, const std::vector<Ray>& rays, Query query, std::vector<Hit>& hits,
               std::vector<TraversalCounters>* counters = nullptr);
/// The same over a two-level BVH, BVH2 or CWBVH BLAS: hits name triangles by scene-wide ids
/// (TwoLevelBvh).
void trace_cpu(const accel::TwoLevelBvh& bvh, const std::vector<Ray>& rays, Query query, std::vector<Hit>& hits,
               std::vector<TraversalCounters>* counters = nullptr);

}  // namespace bvhlab::trav
