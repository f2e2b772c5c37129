// SPDX-License-Identifier: MIT
// CPU tracer for kd-trees: the shared kd traversal over a ray set, in parallel with TBB.
#pragma once

#include <vector>

#include "accel/core/mesh.h"
#include "accel/layouts/kd_node.h"
#include "accel/layouts/woop_tri.h"
#include "traversal/device/bvh2_traverse.h"
#include "traversal/device/ray.h"

namespace bvhlab::trav {

/// A kd-tree with the Woop triangles its traversal needs (one per mesh triangle). Owns them.
struct KdTracer {
    accel::KdTree tree;
    std::vector<accel::WoopTriangle> tris;
    int stack_limit = 64;  ///< 64 = full stack; 1..8 = short stack with restart

    KdTracer(accel::KdTree t, const accel::TriangleMesh& mesh, int stack = 64);
};

/// Traces every ray; fills `counters` too when it is non-null.
void trace_kd_cpu(const KdTracer& kd, const std::vector<Ray>& rays, Query query, std::vector<Hit>& hits,
                  std::vector<TraversalCounters>* counters = nullptr);

}  // namespace bvhlab::trav
