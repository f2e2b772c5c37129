// SPDX-License-Identifier: MIT
#include "traversal/gpu/device_structure.h"

#include "accel/core/check.h"

namespace bvhlab::trav {

DeviceStructure::DeviceStructure(const Structure& s, DeviceBuffer<accel::Bvh2Node>&& nodes,
                                 DeviceBuffer<accel::WoopTriangle>&& tris, DeviceBuffer<uint32_t>&& tri_ids)
    : layout_(s.layout),
      depth_(s.depth()),
      bvh_nodes_(std::move(nodes)),
      bvh_tris_(std::move(tris)),
      bvh_ids_(std::move(tri_ids)) {
    BVHLAB_CHECK(s.layout == Layout::kBvh2 && bvh_nodes_.size() == s.bvh2.nodes.size() &&
                     bvh_tris_.size() == s.bvh2.tris.size() && bvh_ids_.size() == s.bvh2.tri_ids.size(),
                 "a device BVH2 is adopted only with its own host copy");
}

DeviceStructure::DeviceStructure(const Structure& s) : layout_(s.layout), depth_(s.depth()) {
    std::string why;
    if (!gpu_available(&why)) throw Error(why);
    if (s.layout == Layout::kBvh2) {
        bvh_nodes_.upload(s.bvh2.nodes);
        bvh_tris_.upload(s.bvh2.tris);
        bvh_ids_.upload(s.bvh2.tri_ids);
    } else if (s.layout == Layout::kCwbvh) {
        cw_nodes_.upload(s.cwbvh.nodes);
        bvh_tris_.upload(s.cwbvh.tris);
        cw_vtris_.upload(s.cwbvh.vtris);
        bvh_ids_.upload(s.cwbvh.tri_ids);
    } else if (s.layout == Layout::kTwoLevelCwbvh) {
        const accel::TwoLevelBvh& t = s.two_level;
        bvh_nodes_.upload(t.tlas.nodes);  // the BVH2 form of the TLAS, for the kernel that walks it
        bvh_ids_.upload(t.tlas.tri_ids);
        cw_tlas_nodes_.upload(t.cw_tlas.nodes);
        cw_tlas_ids_.upload(t.cw_tlas.tri_ids);
        instances_.upload(t.instances);
        // Every BLAS in one set of buffers; each view points at its own part (child and triangle
        // bases in a CWBVH node are relative to its own arrays).
        std::vector<accel::CwbvhNode> nodes;
        std::vector<accel::WoopTriangle> tris;
        std::vector<accel::VertexTriangle> vtris;
        std::vector<uint32_t> ids;
        std::vector<size_t> node_at, tri_at, vtri_at, id_at;
        for (const accel::Cwbvh& b : t.cw_blas) {
            node_at.push_back(nodes.size());
            tri_at.push_back(tris.size());
            vtri_at.push_back(vtris.size());
            id_at.push_back(ids.size());
            nodes.insert(nodes.end(), b.nodes.begin(), b.nodes.end());
            tris.insert(tris.end(), b.tris.begin(), b.tris.end());
            vtris.insert(vtris.end(), b.vtris.begin(), b.vtris.end());
            ids.insert(ids.end(), b.tri_ids.begin(), b.tri_ids.end());
        }
        cw_nodes_.upload(nodes);
        blas_tris_.upload(tris);
        cw_vtris_.upload(vtris);
        blas_ids_.upload(ids);
        std::vector<CwbvhView> views;
        for (size_t m = 0; m < t.cw_blas.size(); ++m) {
            const bool woop = t.cw_blas[m].tri_format == accel::CwTris::kWoop;
            cw_vertices_ = !woop;  // one format for every BLAS (build_two_level's BlasLayout)
            views.push_back({cw_nodes_.data() + node_at[m], woop ? blas_tris_.data() + tri_at[m] : nullptr,
                             blas_ids_.data() + id_at[m], woop ? nullptr : cw_vtris_.data() + vtri_at[m]});
        }
        cw_views_.upload(views);
    } else if (s.layout == Layout::kTwoLevel) {
        const accel::TwoLevelBvh& t = s.two_level;
        blas_depth_ = t.blas_depth();
        bvh_nodes_.upload(t.tlas.nodes);
        bvh_ids_.upload(t.tlas.tri_ids);
        instances_.upload(t.instances);
        // Every BLAS in one set of buffers; each view points at its own part.
        std::vector<accel::Bvh2Node> nodes;
        std::vector<accel::WoopTriangle> tris;
        std::vector<uint32_t> ids;
        std::vector<size_t> node_at, tri_at;
        for (const accel::Bvh2& b : t.blas) {
            node_at.push_back(nodes.size());
            tri_at.push_back(tris.size());
            nodes.insert(nodes.end(), b.nodes.begin(), b.nodes.end());
            tris.insert(tris.end(), b.tris.begin(), b.tris.end());
            ids.insert(ids.end(), b.tri_ids.begin(), b.tri_ids.end());
        }
        blas_nodes_.upload(nodes);
        blas_tris_.upload(tris);
        blas_ids_.upload(ids);
        std::vector<Bvh2View> views;
        for (size_t m = 0; m < t.blas.size(); ++m)
            views.push_back(
                {blas_nodes_.data() + node_at[m], blas_tris_.data() + tri_at[m], blas_ids_.data() + tri_at[m]});
        blas_views_.upload(views);
    } else {
        kd_nodes_.upload(s.kd.tree.nodes);
        kd_prims_.upload(s.kd.tree.prim_indices);
        kd_tris_.upload(s.kd.tris);
        kd_bounds_ = s.kd.tree.bounds;
    }
}

void DeviceStructure::replace_tlas(DeviceBuffer<accel::Bvh2Node>&& nodes, DeviceBuffer<uint32_t>&& instance_ids,
                                   DeviceBuffer<accel::InstanceRecord>&& records, uint32_t depth) {
    if (layout_ != Layout::kTwoLevel) throw Error("only a two-level BVH2 structure has a TLAS to replace");
    bvh_nodes_ = std::move(nodes);
    bvh_ids_ = std::move(instance_ids);
    instances_ = std::move(records);
    depth_ = std::max(depth, blas_depth_);
}

size_t DeviceStructure::bytes() const {
    return bvh_nodes_.bytes() + cw_nodes_.bytes() + bvh_tris_.bytes() + bvh_ids_.bytes() + cw_vtris_.bytes() +
           kd_nodes_.bytes() + kd_prims_.bytes() + kd_tris_.bytes() + instances_.bytes() + blas_nodes_.bytes() +
           blas_tris_.bytes() + blas_ids_.bytes() + blas_views_.bytes() + cw_views_.bytes() + cw_tlas_nodes_.bytes() +
           cw_tlas_ids_.bytes();
}

}  // namespace bvhlab::trav
