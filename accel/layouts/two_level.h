// SPDX-License-Identifier: MIT
// A two-level BVH: one bottom-level BVH (BLAS) per mesh, in the mesh's own space, in the BVH2 or
// the compressed 8-wide layout, and a top-level BVH2 (TLAS) over the instances' world boxes, one
// instance per leaf entry. A ray reaching an instance is moved into the instance's space and
// traced through its mesh's BLAS (traversal/device/two_level_traverse.h and
// two_level_cwbvh_traverse.h), as in Embree, OptiX and tinybvh.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "accel/core/build_tree.h"
#include "accel/layouts/bvh2_node.h"
#include "accel/layouts/cwbvh_node.h"
#include "accel/passes/collapse_wide.h"
#include "scene/scene.h"

namespace bvhlab::accel {

/// An instance as the traversal reads it, 64 bytes.
struct alignas(16) InstanceRecord {
    float world_to_object[12];  ///< rows of the inverse of the instance's [M | t]
    uint32_t blas;              ///< the BLAS of its mesh
    uint32_t first_id;          ///< the scene-wide id of its triangle 0 (see TwoLevelBvh)
    uint32_t reserved[2];       ///< zero

    BVHLAB_HD Vec3 point(Vec3 p) const {
        const float* m = world_to_object;
        return {m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3], m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
                m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]};
    }
    BVHLAB_HD Vec3 vector(Vec3 v) const {
        const float* m = world_to_object;
        return {m[0] * v.x + m[1] * v.y + m[2] * v.z, m[4] * v.x + m[5] * v.y + m[6] * v.z,
                m[8] * v.x + m[9] * v.y + m[10] * v.z};
    }
};
static_assert(sizeof(InstanceRecord) == 64 && alignof(InstanceRecord) == 16, "InstanceRecord layout");

/// Hits of a two-level BVH name triangles by scene-wide ids: instance i's triangle k is
/// first_id(i) + k, where first_id counts the triangles of the instances before i. These are the
/// ids of flatten()'s mesh (when no transform degenerates a triangle), so one id says both the
/// instance and its triangle (instance_of_id), and every single-level tool (the comparison,
/// hit files) reads two-level hits unchanged. At most 2^31 - 1 triangles in the world.
struct TwoLevelBvh {
    /// One per mesh of the scene when the BLAS are BVH2s (an empty Bvh2 for a mesh no instance
    /// places); empty when they are CWBVHs.
    std::vector<Bvh2> blas;
    /// One per mesh of the scene when the BLAS are CWBVHs (an empty Cwbvh for a mesh no instance
    /// places); empty when they are BVH2s.
    std::vector<Cwbvh> cw_blas;
    Bvh2 tlas;  ///< over instance boxes: tlas.tri_ids are instance indices, no triangles
    /// The same TLAS collapsed to 8-wide (SAH-optimal) and compressed when the BLAS are CWBVHs
    /// (its tri_ids are instance indices, a leaf slot holds up to three), else empty.
    Cwbvh cw_tlas;
    std::vector<InstanceRecord> instances;
    uint64_t world_triangles = 0;  ///< triangles of every instance

    /// Whether the BLAS are CWBVHs.
    bool wide() const { return !cw_blas.empty(); }
    /// Interior nodes on the longest TLAS path, and the deepest BLAS: the two stacks' entries.
    uint32_t tlas_depth() const { return tlas.depth; }
    uint32_t blas_depth() const;
    /// Every stored BLAS once (BVH2 or CWBVH), the TLAS (both forms) and one record per instance.
    size_t bytes() const;
    /// The instance whose id range holds scene-wide triangle id `id` (binary search).
    uint32_t instance_of_id(uint32_t id) const;
};

/// A BVH builder over one mesh, as the caller chooses it (any BVH builder and options).
using MeshBuilder = std::function<BuildTree(const scene::TriangleMesh&)>;

/// The BLAS layout: BVH2 (with Woop triangles), or each binary BLAS collapsed to 8-wide and
/// compressed (Ylitie et al. 2017) as the single-level cwbvh layout is.
struct BlasLayout {
    bool wide = false;
    CollapseMethod collapse = CollapseMethod::kSahOptimal;
    CwTris tris = CwTris::kWoop;
};

/// BLAS levels whose boxes bound an instance in the world (up to 2^levels boxes, 8 corners each).
constexpr int kFrontierLevels = 4;

/// The child boxes of a BVH2 layout's nodes `levels` below the root (fewer where leaves end
/// sooner): the boxes whose transformed corners bound an instance of it, as build_two_level takes
/// them from the binary tree (the same boxes). One box for a root leaf.
std::vector<AABB> frontier_boxes(const Bvh2& bvh, int levels = kFrontierLevels);

/// Builds the BLAS of every placed mesh with `build` (in `layout`) and a binned-SAH TLAS over the
/// instances' world boxes: the transformed corners of the binary BLAS's boxes four levels below
/// its root (up to 16 boxes), far tighter than the root box's corners for a turned instance.
/// Throws bvhlab::Error for a scene without instances or with more than 2^31 - 1 world
/// triangles, and for a singular instance transform.
TwoLevelBvh build_two_level(const scene::InstancedScene& scene, const MeshBuilder& build,
                            const BlasLayout& layout = {});

}  // namespace bvhlab::accel
