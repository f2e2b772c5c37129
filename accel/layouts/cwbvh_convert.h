// SPDX-License-Identifier: MIT
// WideTree -> Cwbvh: octant-ordered child slots, conservatively quantised child boxes, Woop or
// vertex triangles in leaf order.
#pragma once

#include <array>
#include <vector>

#include "accel/layouts/cwbvh_node.h"
#include "accel/passes/collapse_wide.h"
#include "scene/mesh.h"

namespace bvhlab::accel {

/// Converts a wide tree over `mesh`. Throws bvhlab::Error when a node's extent is beyond what
/// the traversal's scaled reciprocals can hold (more than 255 * 2^31 on an axis). With
/// `slot_boxes`, also returns for each output node the exact box of the child in each slot
/// (empty slots: AABB::empty()), for the conservativeness tests.
Cwbvh convert_to_cwbvh(const WideTree& tree, const scene::TriangleMesh& mesh, CwTris tri_format = CwTris::kWoop,
                       std::vector<std::array<AABB, kWideArity>>* slot_boxes = nullptr);

/// The nodes, leaf references (tri_ids = the wide tree's prim_indices in leaf order) and depth of
/// the same conversion, without triangles: for trees over other primitives (the two-level top
/// level, whose references are instances).
Cwbvh convert_cwbvh_nodes(const WideTree& tree, std::vector<std::array<AABB, kWideArity>>* slot_boxes = nullptr);

/// The box slot `slot` of `node` decodes to, in double precision (exact for every scene the
/// converter accepts): what the conservativeness tests compare with the exact child boxes.
AABB decode_child_box(const CwbvhNode& node, uint32_t slot, double* lo = nullptr, double* hi = nullptr);

}  // namespace bvhlab::accel
