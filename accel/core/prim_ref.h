// SPDX-License-Identifier: MIT
// A primitive reference as the builders move it around: its bounds and its triangle id.
#pragma once

#include <cstdint>
#include <vector>

#include "accel/core/aabb.h"
#include "scene/mesh.h"

namespace bvhlab::accel {

/// Bounds of one reference plus the triangle it stands for, 28 bytes. Builders partition
/// arrays of these in place, so a node's references stay contiguous and cache-friendly.
struct PrimRef {
    AABB bounds;       // 24 bytes
    uint32_t prim_id;  // 4 bytes: total 28 bytes

    Vec3 centroid() const { return bounds.center(); }
};

/// One reference per triangle of `mesh`, in triangle order (parallel).
std::vector<PrimRef> make_prim_refs(const scene::TriangleMesh& mesh);

}  // namespace bvhlab::accel
