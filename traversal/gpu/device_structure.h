// SPDX-License-Identifier: MIT
// A Structure uploaded to the GPU, whatever its layout, with the plain view struct that its
// kernels take (Bvh2View, CwbvhView or KdView, written once for host and device).
#pragma once

#include "accel/core/aabb.h"
#include "traversal/device/bvh2_traverse.h"
#include "traversal/device/cwbvh_traverse.h"
#include "traversal/device/kd_traverse.h"
#include "traversal/device/two_level_traverse.h"
#include "traversal/gpu/device_buffer.h"
#include "traversal/structure.h"

namespace bvhlab::trav {

class DeviceStructure {
public:
    /// Uploads the structure's layout. Throws bvhlab::Error (CudaError) on failure.
    explicit DeviceStructure(const Structure& s);
    /// Adopts a BVH2 layout that is on the device already (a GPU builder's); `s` holds the same
    /// structure on the host. Nothing is uploaded.
    DeviceStructure(const Structure& s, DeviceBuffer<accel::Bvh2Node>&& nodes, DeviceBuffer<accel::WoopTriangle>&& tris,
                    DeviceBuffer<uint32_t>&& tri_ids);

    Layout layout() const { return layout_; }
    uint32_t depth() const { return depth_; }

    /// The device view of a BVH2 layout (null pointers for the other layouts).
    Bvh2View bvh2() const { return {bvh_nodes_.data(), bvh_tris_.data(), bvh_ids_.data()}; }
    /// The device view of a kd layout (null pointers for the other layouts).
    KdView kd() const { return {kd_nodes_.data(), kd_prims_.data(), kd_tris_.data(), kd_bounds_}; }
    /// The device view of a CWBVH layout (null pointers for the other layouts).
    CwbvhView cwbvh() const { return {cw_nodes_.data(), bvh_tris_.data(), bvh_ids_.data(), cw_vtris_.data()}; }
    /// The device view of a two-level layout (null pointers for the other layouts): the TLAS in
    /// the BVH2 buffers (its ids are instance indices), every BLAS concatenated behind it (the
    /// BVH2 BLAS views, or the CWBVH ones, null for the other kind).
    TwoLevelView two_level() const {
        TwoLevelView v{bvh_nodes_.data(),  bvh_ids_.data(),  instances_.data(),
                       blas_views_.data(), cw_views_.data(), cw_vertices_};
        v.cw_tlas = cw_tlas_nodes_.data();
        v.cw_tlas_ids = cw_tlas_ids_.data();
        return v;
    }

    /// Device memory of every buffer the structure uploaded.
    size_t bytes() const;

    /// A single-level BVH2 layout's nodes and triangles, writable, for a refit (GpuRefitter).
    accel::Bvh2Node* bvh2_nodes_for_refit() { return bvh_nodes_.data(); }
    accel::WoopTriangle* bvh2_tris_for_refit() { return bvh_tris_.data(); }

    /// A two-level BVH2 structure's TLAS replaced by one built on the device (GpuTlasBuilder):
    /// its nodes, instance ids, instance records and depth. Throws bvhlab::Error for another
    /// layout.
    void replace_tlas(DeviceBuffer<accel::Bvh2Node>&& nodes, DeviceBuffer<uint32_t>&& instance_ids,
                      DeviceBuffer<accel::InstanceRecord>&& records, uint32_t depth);

private:
    Layout layout_;
    uint32_t depth_;
    DeviceBuffer<accel::Bvh2Node> bvh_nodes_;
    DeviceBuffer<accel::CwbvhNode> cw_nodes_;
    DeviceBuffer<accel::WoopTriangle> bvh_tris_;  // the BVH2's or the CWBVH's triangles
    DeviceBuffer<uint32_t> bvh_ids_;
    DeviceBuffer<accel::VertexTriangle> cw_vtris_;  // a CWBVH's triangles with CwTris::kVertices
    DeviceBuffer<accel::KdNode> kd_nodes_;
    DeviceBuffer<uint32_t> kd_prims_;
    DeviceBuffer<accel::WoopTriangle> kd_tris_;
    AABB kd_bounds_ = AABB::empty();
    DeviceBuffer<accel::InstanceRecord> instances_;
    uint32_t blas_depth_ = 0;  // two-level layouts: the deepest BLAS
    DeviceBuffer<accel::Bvh2Node> blas_nodes_;
    DeviceBuffer<accel::WoopTriangle> blas_tris_;
    DeviceBuffer<uint32_t> blas_ids_;
    DeviceBuffer<Bvh2View> blas_views_;  // one per BVH2 BLAS, pointing into the three buffers above
    bool cw_vertices_ = false;           // the CWBVH BLAS hold vertex triangles
    DeviceBuffer<CwbvhView> cw_views_;
    DeviceBuffer<accel::CwbvhNode> cw_tlas_nodes_;  // the 8-wide TLAS of a two-level-cwbvh layout
    DeviceBuffer<uint32_t> cw_tlas_ids_;  // one per CWBVH BLAS, into cw_nodes_, blas_tris_, blas_ids_, cw_vtris_
};

}  // namespace bvhlab::trav
