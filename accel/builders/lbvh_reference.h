// SPDX-License-Identifier: MIT
// The linear BVH on the CPU, step by step as the GPU builder makes it (Morton codes, a stable
// sort, Karras's hierarchy, bottom-up boxes): the reference that the GPU's LBVH is compared
// with bit for bit. Not a builder of its own: one thread, single-triangle leaves.
#pragma once

#include <cstdint>
#include <vector>

#include "accel/core/aabb.h"
#include "scene/mesh.h"

namespace bvhlab::accel {

/// A binary hierarchy with one triangle per leaf, as the GPU builders emit it before their leaves
/// are collapsed. Node ids: leaf k (0 <= k < n) holds triangle sorted_ids[k]; interior nodes
/// are n .. 2n - 2 (Karras's interior node i is n + i, so the root of an LBVH is n).
struct RawHierarchy {
    uint32_t root = 0;
    std::vector<uint64_t> keys;         ///< the Morton codes in sorted order
    std::vector<uint32_t> sorted_ids;   ///< triangle ids in key order (ties by id)
    std::vector<uint32_t> left, right;  ///< children of interior node n + i at [i]
    std::vector<AABB> boxes;            ///< every node's box, by node id

    size_t interior_count() const { return left.size(); }
};

/// The LBVH of `mesh` with `morton_bits` (30 or 60) bit codes of the triangle boxes' centres in
/// the centres' bounding box. Throws bvhlab::Error for an empty mesh or other bit counts.
RawHierarchy lbvh_reference(const scene::TriangleMesh& mesh, int morton_bits);

}  // namespace bvhlab::accel
